// insdiag.v1 FleetService messages ⇄ the fleet store's domain values
// (kb/fleet_statistics.h): requests become queries, results responses (a
// time the result does not hold stays unset). The mapping sits at the API
// edge so that kb knows nothing of the wire format.
#pragma once

#include "insdiag/kb/fleet_statistics.h"
#include "insdiag/v1/fleet.pb.h"

namespace insdiag::server {

kb::FleetStatisticsQuery FromProto(const v1::GetFleetStatisticsRequest& request);
kb::FailureCountQuery FromProto(const v1::ListFailureCountsRequest& request);
kb::FailureParetoQuery FromProto(const v1::GetFailureParetoRequest& request);
kb::WeibullFitQuery FromProto(const v1::GetWeibullFitRequest& request);
kb::ParameterPointQuery FromProto(const v1::ListParameterTrendsRequest& request);
kb::ParameterTrendQuery FromProto(const v1::GetParameterTrendRequest& request);
kb::UnitRankingQuery FromProto(const v1::RankUnitsRequest& request);

v1::FleetStatistics ToProto(const kb::FleetStatistics& statistics);
v1::ListFailureCountsResponse ToProto(const kb::FailureCounts& counts);
v1::FailurePareto ToProto(const kb::FailurePareto& pareto);
v1::WeibullFit ToProto(const kb::WeibullFit& fit);
v1::ListParameterTrendsResponse ToProto(const kb::ParameterPointPage& page);
v1::ParameterTrend ToProto(const kb::ParameterTrend& trend);
v1::RankUnitsResponse ToProto(const kb::UnitRankingPage& page);

}  // namespace insdiag::server
