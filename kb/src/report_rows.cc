#include "report_rows.h"

#include <absl/strings/str_cat.h>

#include <bit>
#include <cstdint>

#include "insdiag/api/resource_names.h"
#include "insdiag/engine/status_macros.h"
#include "store_util.h"

namespace insdiag::kb::internal {
namespace {

constexpr char kRebuiltNote[] =
    "rebuilt from the knowledge base's rows: this analysis was stored without its full report (e.g. generated fleet "
    "history), so only the verdict, headline figures, identified parameters, effect candidates, channel metrics "
    "and fault intervals are present";

absl::Status AddCandidates(Connection& db, const std::string& analysis_id, v1::AnalysisReport& report) {
  INSDIAG_ASSIGN_OR_RETURN(auto rows,
                           db.Exec("SELECT name, family, source, statistic, degrees_of_freedom, "
                                   "p_value, p_value_holm, estimate, "
                                   "coalesce(std_error, 0), unit, identifiable, "
                                   "coalesce(predicted_delta_aic, 0), per_family "
                                   "FROM effect_candidates WHERE analysis_id = $1::uuid ORDER BY "
                                   "per_family, p_value_holm, name",
                                   {Param::Text(analysis_id)}));
  for (int r = 0; r < rows.rows(); ++r) {
    auto* c = rows.Bool(r, 12) ? report.add_family_candidates() : report.add_effect_candidates();
    c->set_name(rows.String(r, 0));
    c->set_family(rows.String(r, 1));
    c->set_source(rows.String(r, 2));
    c->set_statistic(DoubleOr0(rows, r, 3));
    c->set_degrees_of_freedom(static_cast<int>(IntOr0(rows, r, 4)));
    c->set_p_value(DoubleOr0(rows, r, 5));
    c->set_p_value_holm(DoubleOr0(rows, r, 6));
    c->set_estimate(DoubleOr0(rows, r, 7));
    c->set_std_error(DoubleOr0(rows, r, 8));
    c->set_unit(rows.String(r, 9));
    c->set_identifiable(rows.Bool(r, 10));
    c->set_predicted_delta_aic(DoubleOr0(rows, r, 11));
  }
  return absl::OkStatus();
}

absl::Status AddIdentified(Connection& db, const std::string& analysis_id, v1::AnalysisReport& report) {
  INSDIAG_ASSIGN_OR_RETURN(auto rows, db.Exec("SELECT n.name, p.value, coalesce(p.std_error, 0), "
                                              "p.method, p.a_priori FROM identified_parameters p "
                                              "JOIN parameter_names n USING (parameter_id) WHERE "
                                              "p.analysis_id = $1::uuid ORDER BY n.name",
                                              {Param::Text(analysis_id)}));
  for (int r = 0; r < rows.rows(); ++r) {
    auto* p = report.add_identified();
    p->set_name(rows.String(r, 0));
    p->set_value(DoubleOr0(rows, r, 1));
    p->set_std_error(DoubleOr0(rows, r, 2));
    v1::IdentifiedParameter::Method method = v1::IdentifiedParameter::METHOD_UNSPECIFIED;
    v1::IdentifiedParameter::Method_Parse(rows.String(r, 3), &method);
    p->set_method(method);
    if (auto prior = rows.OptionalDouble(r, 4)) p->set_a_priori(*prior);
  }
  return absl::OkStatus();
}

absl::Status AddChannelsAndIntervals(Connection& db, const std::string& analysis_id, v1::AnalysisReport& report) {
  INSDIAG_ASSIGN_OR_RETURN(
      auto channels,
      db.Exec("SELECT channel, rms, fit_percent, nis_mean, whiteness_p_value, sample_count FROM "
              "channel_metrics "
              "WHERE analysis_id = $1::uuid ORDER BY CASE channel WHEN 'lat' THEN 0 WHEN 'lon' "
              "THEN 1 WHEN 'height' THEN 2 "
              "WHEN 'vel_n' THEN 3 WHEN 'vel_e' THEN 4 WHEN 'vel_d' THEN 5 ELSE 6 END, channel",
              {Param::Text(analysis_id)}));
  for (int r = 0; r < channels.rows(); ++r) {
    auto* c = report.add_channels();
    c->set_name(channels.String(r, 0));
    c->set_rms(DoubleOr0(channels, r, 1));
    c->set_fit_percent(DoubleOr0(channels, r, 2));
    c->set_nis_mean(DoubleOr0(channels, r, 3));
    c->set_whiteness_p_value(DoubleOr0(channels, r, 4));
    c->set_sample_count(IntOr0(channels, r, 5));
    c->set_unit(c->name().starts_with("vel_") ? "m/s" : "m");
  }
  INSDIAG_ASSIGN_OR_RETURN(auto intervals,
                           db.Exec("SELECT channel, start_s, end_s, kind, peak_statistic FROM "
                                   "fault_intervals WHERE analysis_id = $1::uuid "
                                   "ORDER BY position",
                                   {Param::Text(analysis_id)}));
  for (int r = 0; r < intervals.rows(); ++r) {
    auto* f = report.add_fault_intervals();
    f->set_channel(intervals.String(r, 0));
    f->set_start_s(DoubleOr0(intervals, r, 1));
    f->set_end_s(DoubleOr0(intervals, r, 2));
    v1::FaultInterval::Kind kind = v1::FaultInterval::KIND_UNSPECIFIED;
    v1::FaultInterval::Kind_Parse(intervals.String(r, 3), &kind);
    f->set_kind(kind);
    f->set_peak_statistic(DoubleOr0(intervals, r, 4));
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<v1::AnalysisReport> RebuildReport(Connection& db, const std::string& analysis_id) {
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows,
      db.Exec(
          "SELECT coalesce(verdict, ''), nis_mean, log_likelihood, aic, bic, request FROM analyses "
          "WHERE analysis_id = $1::uuid",
          {Param::Text(analysis_id)}, ResultFormat::kBinary));
  if (rows.rows() == 0)
    return absl::NotFoundError(
        absl::StrCat(api::ResourceName(api::kAnalyses, analysis_id), " does not exist"));
  v1::AnalysisReport report;
  v1::AnalysisReport::Verdict verdict = v1::AnalysisReport::VERDICT_UNSPECIFIED;
  v1::AnalysisReport::Verdict_Parse(rows.String(0, 0), &verdict);
  report.set_verdict(verdict);
  // Binary float8: big-endian IEEE-754.
  const auto binary_double = [&](int column) {
    if (rows.IsNull(0, column)) return 0.0;
    std::uint64_t bits = 0;
    for (const char c : rows.Get(0, column)) bits = (bits << 8) | static_cast<unsigned char>(c);
    return std::bit_cast<double>(bits);
  };
  report.set_nis_mean(binary_double(1));
  report.set_log_likelihood(binary_double(2));
  report.set_aic(binary_double(3));
  report.set_bic(binary_double(4));
  report.mutable_model()->ParseFromString(rows.String(0, 5));
  INSDIAG_RETURN_IF_ERROR(AddIdentified(db, analysis_id, report));
  INSDIAG_RETURN_IF_ERROR(AddCandidates(db, analysis_id, report));
  INSDIAG_RETURN_IF_ERROR(AddChannelsAndIntervals(db, analysis_id, report));
  report.add_notes(kRebuiltNote);
  return report;
}

absl::StatusOr<v1::AnalysisReport> LoadReport(Connection& db, const std::string& analysis_id) {
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows, db.Exec("SELECT state, report FROM analyses WHERE analysis_id = $1::uuid",
                         {Param::Text(analysis_id)}, ResultFormat::kBinary));
  if (rows.rows() == 0)
    return absl::NotFoundError(
        absl::StrCat(api::ResourceName(api::kAnalyses, analysis_id), " does not exist"));
  if (rows.Get(0, 0) != "SUCCEEDED") {
    return absl::FailedPreconditionError(
        absl::StrCat(api::ResourceName(api::kAnalyses, analysis_id), " is ", rows.String(0, 0),
                     ": only a SUCCEEDED analysis has evidence"));
  }
  if (rows.IsNull(0, 1)) return RebuildReport(db, analysis_id);
  v1::AnalysisReport report;
  report.ParseFromString(std::string(rows.Get(0, 1)));
  return report;
}

}  // namespace insdiag::kb::internal
