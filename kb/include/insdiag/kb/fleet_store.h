// Fleet statistics (docs/FLEET.md): SQL over the knowledge base, the heavy
// aggregates materialised (fleet_counts, parameter_trend_buckets; refreshed
// by RefreshViews), life statistics fitted here (kb/reliability.h). The
// queries and results are in kb/fleet_statistics.h. A malformed query is
// refused INVALID_ARGUMENT naming its field.
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include "insdiag/kb/connection_pool.h"
#include "insdiag/kb/fleet_statistics.h"

namespace insdiag::kb {

class FleetStore {
 public:
  explicit FleetStore(ConnectionPool& pool) : pool_(pool) {}

  absl::StatusOr<FleetStatistics> GetFleetStatistics(const FleetStatisticsQuery& query);
  absl::StatusOr<FailureCounts> ListFailureCounts(const FailureCountQuery& query);
  absl::StatusOr<FailurePareto> GetFailurePareto(const FailureParetoQuery& query);
  // FAILED_PRECONDITION when the data hold fewer than 2 failures.
  absl::StatusOr<WeibullFit> GetWeibullFit(const WeibullFitQuery& query);
  absl::StatusOr<ParameterPointPage> ListParameterTrends(const ParameterPointQuery& query);
  absl::StatusOr<ParameterTrend> GetParameterTrend(const ParameterTrendQuery& query);
  absl::StatusOr<UnitRankingPage> RankUnits(const UnitRankingQuery& query);

  // Refreshes the materialised views; `concurrently`, readers are not
  // blocked (slower: the new contents are diffed into the old). Skipped,
  // returning false, when another process is refreshing.
  absl::StatusOr<bool> RefreshViews(bool concurrently = true);

 private:
  ConnectionPool& pool_;
};

}  // namespace insdiag::kb
