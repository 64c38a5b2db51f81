#include "history_codec.h"

#include <absl/time/time.h>
#include <google/protobuf/timestamp.pb.h>

#include <cstdint>

#include "insdiag/api/report_codec.h"
#include "insdiag/api/time_codec.h"

namespace insdiag::server {
namespace {

v1::RunParameterPoint ToProto(const kb::RunParameterPoint& point) {
  v1::RunParameterPoint message;
  message.set_run(point.run);
  message.set_analysis(point.analysis);
  *message.mutable_test_time() = api::TimestampOf(point.test_time);
  message.set_days(point.days);
  message.set_value(point.value);
  message.set_std_error(point.std_error);
  return message;
}

v1::HistoryAnalysis ToProto(const kb::HistoryAnalysis& analysis) {
  v1::HistoryAnalysis message;
  message.set_analysis(analysis.analysis);
  *message.mutable_create_time() = api::TimestampOf(analysis.create_time);
  message.set_verdict(analysis.verdict.has_value() ? api::ToProto(*analysis.verdict)
                                                   : v1::AnalysisReport::VERDICT_UNSPECIFIED);
  message.set_unit_hours(analysis.unit_hours);
  message.set_counted(analysis.counted);
  message.set_identified_count(analysis.identified_count);
  return message;
}

v1::HistoryRun ToProto(const kb::HistoryRun& run) {
  v1::HistoryRun message;
  message.set_run(run.run);
  *message.mutable_test_time() = api::TimestampOf(run.test_time);
  message.set_duration_s(run.duration_s);
  for (const auto& analysis : run.analyses) *message.add_analyses() = ToProto(analysis);
  return message;
}

}  // namespace

kb::UnitHistoryQuery UnitHistoryQueryOf(const v1::GetUnitHistoryRequest& request) {
  kb::UnitHistoryQuery query;
  query.unit = request.unit();
  query.page_size = request.page_size();
  query.page_token = request.page_token();
  query.parameters.assign(request.parameters().begin(), request.parameters().end());
  query.confidence = request.confidence();
  return query;
}

v1::UnitTrendFit ToProto(const kb::TrendFit& fit) {
  v1::UnitTrendFit message;
  message.set_fitted(fit.fitted);
  message.set_weighted(fit.weighted);
  message.set_slope_per_day(fit.slope_per_day);
  message.set_slope_std_error_per_day(fit.slope_std_error_per_day);
  message.set_intercept(fit.intercept);
  message.set_p_value(fit.p_value);
  message.set_chi_square(fit.chi_square);
  message.set_degrees_of_freedom(fit.degrees_of_freedom);
  message.set_scatter_p_value(fit.scatter_p_value);
  message.set_excess_scatter(fit.excess_scatter);
  message.set_birge_ratio(fit.birge_ratio);
  return message;
}

v1::UnitParameterStatistics ToProto(const kb::ParameterStatistics& statistics) {
  v1::UnitParameterStatistics message;
  message.set_count(statistics.count);
  message.set_mean(statistics.mean);
  message.set_run_to_run_sd(statistics.run_to_run_sd);
  message.set_run_to_run_sd_low(statistics.run_to_run_sd_low);
  message.set_run_to_run_sd_high(statistics.run_to_run_sd_high);
  message.set_rms_std_error(statistics.rms_std_error);
  if (statistics.turn_on_to_turn_on_sd.has_value())
    message.set_turn_on_to_turn_on_sd(*statistics.turn_on_to_turn_on_sd);
  if (statistics.trend.has_value()) *message.mutable_trend() = ToProto(*statistics.trend);
  return message;
}

v1::UnitParameterHistory ToProto(const kb::ParameterHistory& history) {
  v1::UnitParameterHistory message;
  message.set_name(history.name);
  message.set_unit(history.unit);
  message.set_turn_on_bias(history.turn_on_bias);
  for (const auto& point : history.points) *message.add_points() = ToProto(point);
  *message.mutable_statistics() = ToProto(history.statistics);
  return message;
}

v1::UnitHistory ToProto(const kb::UnitHistory& history) {
  v1::UnitHistory message;
  message.set_unit(history.unit);
  message.set_unit_type(history.unit_type);
  for (const auto& run : history.runs) *message.add_runs() = ToProto(run);
  message.set_next_page_token(history.next_page_token);
  for (const auto& parameter : history.parameters) *message.add_parameters() = ToProto(parameter);
  message.set_run_count(history.run_count);
  message.set_analysed_run_count(history.analysed_run_count);
  message.set_confidence(history.confidence);
  for (const auto& note : history.notes) message.add_notes(note);
  return message;
}

}  // namespace insdiag::server
