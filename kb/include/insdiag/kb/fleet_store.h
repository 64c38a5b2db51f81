// Fleet statistics (docs/FLEET.md): SQL over the knowledge base, the heavy
// aggregates materialised (fleet_counts, parameter_trend_buckets; refreshed
// by RefreshViews), life statistics fitted here (kb/reliability.h).
// `unit_type` arguments are unitTypes/{t}; empty means the whole fleet.
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <string>

#include "insdiag/kb/connection_pool.h"
#include "insdiag/v1/fleet.pb.h"

namespace insdiag::kb {

class FleetStore {
 public:
  explicit FleetStore(ConnectionPool& pool) : pool_(pool) {}

  absl::StatusOr<v1::FleetStatistics> GetFleetStatistics(const v1::GetFleetStatisticsRequest& request);
  absl::StatusOr<v1::ListFailureCountsResponse> ListFailureCounts(const v1::ListFailureCountsRequest& request);
  absl::StatusOr<v1::FailurePareto> GetFailurePareto(const v1::GetFailureParetoRequest& request);
  // FAILED_PRECONDITION when the data hold fewer than 2 failures.
  absl::StatusOr<v1::WeibullFit> GetWeibullFit(const v1::GetWeibullFitRequest& request);
  absl::StatusOr<v1::ListParameterTrendsResponse> ListParameterTrends(const v1::ListParameterTrendsRequest& request);
  absl::StatusOr<v1::ParameterTrend> GetParameterTrend(const v1::GetParameterTrendRequest& request);
  absl::StatusOr<v1::RankUnitsResponse> RankUnits(const v1::RankUnitsRequest& request);

  // Refreshes the materialised views; `concurrently`, readers are not
  // blocked (slower: the new contents are diffed into the old). Skipped,
  // returning false, when another process is refreshing.
  absl::StatusOr<bool> RefreshViews(bool concurrently = true);

 private:
  ConnectionPool& pool_;
};

}  // namespace insdiag::kb
