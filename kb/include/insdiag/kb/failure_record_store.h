// Failure records, the refusals database (FRACAS): what was found on a
// unit's module, and every earlier version of a corrected record
// (migrations/0002_knowledge.sql). A record that confirms a failure mode, or
// stops confirming one, refines that mode's signature in the same
// transaction.
#pragma once

#include <absl/status/statusor.h>

#include <string>
#include <utility>
#include <vector>

#include "insdiag/kb/analysis.h"
#include "insdiag/kb/connection_pool.h"
#include "insdiag/kb/failure_record.h"
#include "insdiag/kb/page_query.h"

namespace insdiag::kb {

// Records newest first; each filter applies when not empty.
struct FailureRecordQuery {
  PageQuery page;
  std::string module;  // units/{u}/modules/{role}
  std::string unit;    // units/{u}
  std::string failure_mode;
};

class FailureRecordStore {
 public:
  // `decode_report`: what refining a signature reads of a confirmed case's
  // stored report bytes. `list_pool`: where the listings read (a streaming
  // replica of the database, the server's --read-database-url); null: `pool`.
  FailureRecordStore(ConnectionPool& pool, ReportDecoder decode_report, ConnectionPool* list_pool = nullptr)
      : pool_(pool), list_pool_(list_pool != nullptr ? *list_pool : pool), decode_report_(std::move(decode_report)) {}

  // INVALID_ARGUMENT naming the field for a malformed record; NOT_FOUND for
  // an unknown module, mode or analysis.
  // `record`'s name, diagnosis, record time and revision are the store's to
  // set.
  absl::StatusOr<FailureRecord> Create(const FailureRecord& record);
  // The record takes `facts` (failure_mode, operating_hours, detected_time
  // when set, confirmed, no_fault_found, censored, repaired, repair_action,
  // notes; the rest is ignored), and the version it replaces is kept with
  // `reason`, in one transaction; confirmed modes it leaves or joins are
  // refined again.
  absl::StatusOr<FailureRecord> Correct(const std::string& name, const FailureRecord& facts,
                                        const std::string& reason);
  // The versions a record replaced, oldest first.
  absl::StatusOr<std::vector<FailureRecordRevision>> ListRevisions(const std::string& name);
  absl::StatusOr<std::pair<std::vector<FailureRecord>, std::string>> List(const FailureRecordQuery& query);

 private:
  ConnectionPool& pool_;
  ConnectionPool& list_pool_;
  ReportDecoder decode_report_;
};

}  // namespace insdiag::kb
