// A unit's history: its runs with their succeeded analyses in test-time
// order, and each identified parameter's points, repeatability and trend
// across the runs (the statistics are kb/unit_history.h). Reads only. Its API
// form is proto/insdiag/v1/history.proto, which the server maps to and from.
#pragma once

#include <absl/status/statusor.h>
#include <absl/time/time.h>

#include <optional>
#include <string>
#include <vector>

#include "insdiag/engine/monitor/monitoring.h"
#include "insdiag/kb/connection_pool.h"
#include "insdiag/kb/unit_history.h"

namespace insdiag::kb {

struct UnitHistoryQuery {
  std::string unit;  // units/{unit}
  // The runs listed, oldest first; the parameters' statistics are always over
  // every run of the unit. page_size 0: the default.
  int page_size = 0;
  std::string page_token;
  std::vector<std::string> parameters;  // only these (e.g. "gyro_turn_on_bias.x"); all when empty
  double confidence = 0.0;  // of the repeatability intervals; 0: 0.95
};

struct HistoryAnalysis {
  std::string analysis;  // analyses/{analysis}
  absl::Time create_time;
  std::optional<engine::Verdict> verdict;  // absent: none stored
  double unit_hours = 0.0;  // the unit's operating hours at the test
  // The run's latest succeeded analysis: the one whose identified values are
  // the run's points in the statistics.
  bool counted = false;
  int identified_count = 0;
};

struct HistoryRun {
  std::string run;       // runs/{run}
  absl::Time test_time;  // when the bench test happened (else the upload)
  double duration_s = 0.0;
  std::vector<HistoryAnalysis> analyses;  // succeeded, oldest first
};

struct UnitHistory {
  std::string unit;       // units/{unit}
  std::string unit_type;  // unitTypes/{unit_type}; empty when unknown
  std::vector<HistoryRun> runs;  // oldest first (the page)
  std::string next_page_token;   // empty on the last page
  std::vector<ParameterHistory> parameters;  // by name
  int run_count = 0;           // runs of the unit
  int analysed_run_count = 0;  // runs with a succeeded analysis: the points of the statistics
  double confidence = 0.0;     // the one used
  std::vector<std::string> notes;
};

class UnitHistoryStore {
 public:
  // `list_pool`: where it reads (a streaming replica of the database, the
  // server's --read-database-url); null: `pool`.
  explicit UnitHistoryStore(ConnectionPool& pool, ConnectionPool* list_pool = nullptr)
      : pool_(list_pool != nullptr ? *list_pool : pool) {}

  // NOT_FOUND for an unknown unit; INVALID_ARGUMENT for a malformed name,
  // page token or confidence outside (0, 1).
  absl::StatusOr<UnitHistory> Get(const UnitHistoryQuery& query);

 private:
  ConnectionPool& pool_;
};

}  // namespace insdiag::kb
