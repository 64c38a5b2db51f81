#include "fleet_codec.h"

#include <absl/time/time.h>

#include <cstdint>

#include "insdiag/api/time_codec.h"

namespace insdiag::server {

kb::FleetStatisticsQuery FromProto(const v1::GetFleetStatisticsRequest& request) {
  kb::FleetStatisticsQuery query;
  query.unit_type = request.unit_type();
  query.confidence = request.confidence();
  return query;
}

kb::FailureCountQuery FromProto(const v1::ListFailureCountsRequest& request) {
  kb::FailureCountQuery query;
  query.unit_type = request.unit_type();
  query.period = request.period();
  if (request.has_start_time()) query.start_time = api::MicrosecondTimeOf(request.start_time());
  if (request.has_end_time()) query.end_time = api::MicrosecondTimeOf(request.end_time());
  query.failure_mode = request.failure_mode();
  query.batch = request.batch();
  return query;
}

kb::FailureParetoQuery FromProto(const v1::GetFailureParetoRequest& request) {
  kb::FailureParetoQuery query;
  query.unit_type = request.unit_type();
  return query;
}

kb::WeibullFitQuery FromProto(const v1::GetWeibullFitRequest& request) {
  kb::WeibullFitQuery query;
  query.unit_type = request.unit_type();
  query.module_role = request.module_role();
  query.failure_mode = request.failure_mode();
  query.confidence = request.confidence();
  return query;
}

kb::ParameterPointQuery FromProto(const v1::ListParameterTrendsRequest& request) {
  kb::ParameterPointQuery query;
  query.unit_type = request.unit_type();
  query.parameter = request.parameter();
  query.unit = request.unit();
  query.page.page_size = request.page_size();
  query.page.page_token = request.page_token();
  return query;
}

kb::ParameterTrendQuery FromProto(const v1::GetParameterTrendRequest& request) {
  kb::ParameterTrendQuery query;
  query.unit_type = request.unit_type();
  query.parameter = request.parameter();
  query.batch = request.batch();
  return query;
}

kb::UnitRankingQuery FromProto(const v1::RankUnitsRequest& request) {
  kb::UnitRankingQuery query;
  query.unit_type = request.unit_type();
  query.page.page_size = request.page_size();
  query.page.page_token = request.page_token();
  return query;
}

v1::FleetStatistics ToProto(const kb::FleetStatistics& statistics) {
  v1::FleetStatistics out;
  out.set_unit_type(statistics.unit_type);
  out.set_unit_count(statistics.unit_count);
  out.set_run_count(statistics.run_count);
  out.set_analysis_count(statistics.analysis_count);
  for (const kb::ModuleFailureRate& rate : statistics.failure_rates) {
    v1::ModuleFailureRate* r = out.add_failure_rates();
    r->set_module_role(rate.module_role);
    r->set_failures(rate.failures);
    r->set_operating_hours(rate.operating_hours);
    r->set_failures_per_million_hours(rate.failures_per_million_hours);
    r->set_mtbf_hours(rate.mtbf_hours);
    r->set_mtbf_lower_hours(rate.mtbf_lower_hours);
    r->set_mtbf_upper_hours(rate.mtbf_upper_hours);
    r->set_no_fault_found(rate.no_fault_found);
    r->set_modules(rate.modules);
  }
  out.set_confidence(statistics.confidence);
  out.set_failure_count(statistics.failure_count);
  out.set_no_fault_found_count(statistics.no_fault_found_count);
  if (statistics.counts_time.has_value())
    *out.mutable_counts_time() = api::TimestampOf(*statistics.counts_time);
  return out;
}

v1::ListFailureCountsResponse ToProto(const kb::FailureCounts& counts) {
  v1::ListFailureCountsResponse out;
  for (const kb::FailureCount& count : counts.counts) {
    v1::FailureCount* c = out.add_counts();
    c->set_failure_mode(count.failure_mode);
    c->set_module_role(count.module_role);
    c->set_unit_type(count.unit_type);
    c->set_batch(count.batch);
    *c->mutable_period_start() = api::TimestampOf(count.period_start);
    c->set_failures(count.failures);
  }
  out.set_total(counts.total);
  return out;
}

v1::FailurePareto ToProto(const kb::FailurePareto& pareto) {
  v1::FailurePareto out;
  out.set_unit_type(pareto.unit_type);
  out.set_total_failures(pareto.total_failures);
  for (const kb::ParetoEntry& entry : pareto.entries) {
    v1::ParetoEntry* e = out.add_entries();
    e->set_failure_mode(entry.failure_mode);
    e->set_module_role(entry.module_role);
    e->set_display_name(entry.display_name);
    e->set_failures(entry.failures);
    e->set_share(entry.share);
    e->set_cumulative_share(entry.cumulative_share);
  }
  return out;
}

v1::WeibullFit ToProto(const kb::WeibullFit& fit) {
  const kb::WeibullEstimate& estimate = fit.estimate;
  v1::WeibullFit out;
  out.set_unit_type(fit.unit_type);
  out.set_module_role(fit.module_role);
  out.set_failure_mode(fit.failure_mode);
  out.set_failures(estimate.failures);
  out.set_suspensions(estimate.suspensions);
  out.set_shape(estimate.shape);
  out.set_scale_hours(estimate.scale_hours);
  out.set_shape_std_error(estimate.shape_std_error);
  out.set_scale_std_error_hours(estimate.scale_std_error_hours);
  out.set_shape_lower(estimate.shape_lower);
  out.set_shape_upper(estimate.shape_upper);
  out.set_scale_lower_hours(estimate.scale_lower_hours);
  out.set_scale_upper_hours(estimate.scale_upper_hours);
  out.set_b10_hours(estimate.b10_hours);
  out.set_b10_lower_hours(estimate.b10_lower_hours);
  out.set_b10_upper_hours(estimate.b10_upper_hours);
  out.set_log_likelihood(estimate.log_likelihood);
  out.set_confidence(fit.confidence);
  return out;
}

v1::ListParameterTrendsResponse ToProto(const kb::ParameterPointPage& page) {
  v1::ListParameterTrendsResponse out;
  for (const kb::ParameterPoint& point : page.points) {
    v1::ParameterPoint* p = out.add_points();
    p->set_unit(point.unit);
    p->set_analysis(point.analysis);
    p->set_operating_hours(point.operating_hours);
    p->set_value(point.value);
    p->set_std_error(point.std_error);
    *p->mutable_time() = api::TimestampOf(point.time);
  }
  out.set_next_page_token(page.next_page_token);
  return out;
}

v1::ParameterTrend ToProto(const kb::ParameterTrend& trend) {
  v1::ParameterTrend out;
  out.set_unit_type(trend.unit_type);
  out.set_parameter(trend.parameter);
  out.set_unit(trend.unit);
  out.set_nominal(trend.nominal);
  out.set_tolerance(trend.tolerance);
  for (const kb::TrendBucket& bucket : trend.buckets) {
    v1::TrendBucket* b = out.add_buckets();
    b->set_batch(bucket.batch);
    *b->mutable_month() = api::TimestampOf(bucket.month);
    b->set_count(bucket.count);
    b->set_median(bucket.median);
    b->set_p25(bucket.p25);
    b->set_p75(bucket.p75);
    b->set_mean(bucket.mean);
  }
  out.set_slope_per_year(trend.slope_per_year);
  out.set_relative_slope_per_year(trend.relative_slope_per_year);
  if (trend.refreshed_time.has_value())
    *out.mutable_refreshed_time() = api::TimestampOf(*trend.refreshed_time);
  return out;
}

v1::RankUnitsResponse ToProto(const kb::UnitRankingPage& page) {
  v1::RankUnitsResponse out;
  for (const kb::RankedUnit& unit : page.units) {
    v1::RankedUnit* u = out.add_units();
    u->set_unit(unit.unit);
    u->set_unit_type(unit.unit_type);
    u->set_batch(unit.batch);
    u->set_fault_probability(unit.fault_probability);
    u->set_top_module(unit.top_module);
    u->set_top_failure_mode(unit.top_failure_mode);
    u->set_top_probability(unit.top_probability);
    u->set_diagnosis(unit.diagnosis);
    u->set_operating_hours(unit.operating_hours);
  }
  out.set_next_page_token(page.next_page_token);
  return out;
}

}  // namespace insdiag::server
