// A unit's identified parameters over its runs, as the unit history and the
// diagnosis read them: one point per run, its latest SUCCEEDED analysis.
#pragma once

#include <absl/status/statusor.h>

#include <string>
#include <vector>

#include "insdiag/kb/pg.h"
#include "insdiag/kb/unit_history.h"

namespace insdiag::kb::internal {

// The test time of a run as SQL: when the bench test happened, else its upload.
inline constexpr char kRunTestTime[] = "coalesce(r.test_time, r.create_time)";

struct HistoryScope {
  std::string unit_id;  // units.unit_id
  // When set (an analysis id): only the runs tested no later than this
  // analysis's run, and this analysis standing for its own run — the
  // history as it was when that analysis was made.
  std::string until_analysis_id;
  std::vector<std::string> only_parameters;  // all when empty
};

// Each parameter's points (oldest first, days from its first point) and
// statistics, by parameter name; the unit of each from the engine's model.
absl::StatusOr<std::vector<ParameterHistory>> LoadParameterHistories(Connection& db, const HistoryScope& scope,
                                                                     const HistoryOptions& options);

}  // namespace insdiag::kb::internal
