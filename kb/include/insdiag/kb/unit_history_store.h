// A unit's history (proto/insdiag/v1/history.proto): its runs with their
// succeeded analyses in test-time order, and each identified parameter's
// points, repeatability and trend across the runs (the statistics are
// kb/unit_history.h). Reads only.
#pragma once

#include <absl/status/statusor.h>

#include "insdiag/kb/connection_pool.h"
#include "insdiag/v1/history.pb.h"

namespace insdiag::kb {

class UnitHistoryStore {
 public:
  // `list_pool`: where it reads (a streaming replica of the database, the
  // server's --read-database-url); null: `pool`.
  explicit UnitHistoryStore(ConnectionPool& pool, ConnectionPool* list_pool = nullptr)
      : pool_(list_pool != nullptr ? *list_pool : pool) {}

  // NOT_FOUND for an unknown unit; INVALID_ARGUMENT for a malformed name,
  // page token or confidence outside (0, 1).
  absl::StatusOr<v1::UnitHistory> Get(const v1::GetUnitHistoryRequest& request);

 private:
  ConnectionPool& pool_;
};

}  // namespace insdiag::kb
