// Stored diagnoses: ranking a SUCCEEDED analysis's unit against its unit
// type's failure modes (the math is kb/diagnosis.h), resolving a diagnosis
// into a failure record, and the failure modes' signatures learnt from the
// confirmed cases (migrations/0002_knowledge.sql).
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <string>
#include <utility>
#include <vector>

#include "insdiag/kb/connection_pool.h"
#include "insdiag/kb/page_query.h"
#include "insdiag/v1/knowledge.pb.h"

namespace insdiag::kb {

// Diagnoses newest first; each filter applies when not empty.
struct DiagnosisQuery {
  PageQuery page;
  std::string analysis;  // analyses/{a}
  std::string unit;      // units/{u}
};

class DiagnosisStore {
 public:
  // `list_pool`: where the listings read (a streaming replica of the
  // database, the server's --read-database-url); null: `pool`.
  explicit DiagnosisStore(ConnectionPool& pool, ConnectionPool* list_pool = nullptr)
      : pool_(pool), list_pool_(list_pool != nullptr ? *list_pool : pool) {}

  // Diagnoses a SUCCEEDED analysis against its unit type's failure modes and
  // stores the result. FAILED_PRECONDITION when the analysis has not
  // succeeded or its unit has no known unit type.
  absl::StatusOr<v1::Diagnosis> Create(const std::string& analysis_name);
  absl::StatusOr<v1::Diagnosis> Get(const std::string& name);
  absl::StatusOr<std::pair<std::vector<v1::Diagnosis>, std::string>> List(const DiagnosisQuery& query);
  // Writes the failure record (confirmed, or no fault found) and, when
  // confirmed, refines the mode's signature with the confirmed cases.
  // FAILED_PRECONDITION when already resolved.
  absl::StatusOr<v1::Diagnosis> Resolve(const v1::ResolveDiagnosisRequest& request);

  // Re-derives the signatures of the failure modes with confirmed cases (of
  // one unit type, or all when empty) from those cases, as confirming each
  // would have: after a bulk load such as the fleet generator's.
  absl::Status RefineSignatures(const std::string& unit_type);

 private:
  ConnectionPool& pool_;
  ConnectionPool& list_pool_;
};

}  // namespace insdiag::kb
