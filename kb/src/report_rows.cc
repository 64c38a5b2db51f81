#include "report_rows.h"

#include <absl/strings/str_cat.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <string_view>

#include "insdiag/api/resource_names.h"
#include "insdiag/engine/status_macros.h"
#include "store_util.h"

namespace insdiag::kb {
namespace {

std::optional<engine::Verdict> VerdictNamed(std::string_view name) {
  for (const engine::Verdict v : {engine::Verdict::kGood, engine::Verdict::kOperable, engine::Verdict::kFaulty}) {
    if (name == engine::VerdictName(v)) return v;
  }
  return std::nullopt;
}

std::optional<engine::FaultKind> FaultKindNamed(std::string_view name) {
  for (const engine::FaultKind k : {engine::FaultKind::kOutlier, engine::FaultKind::kGradual, engine::FaultKind::kAbrupt}) {
    if (name == engine::FaultKindName(k)) return k;
  }
  return std::nullopt;
}

// The name the API's enum has for `name`, which the rows keep as text:
// METHOD_UNSPECIFIED for a name it does not know.
std::string MethodNameOf(const std::string& name) {
  constexpr std::array<std::string_view, 5> kMethods = {"ACF", "ALLAN", "FILTER", "ML", "STATIC"};
  for (const std::string_view known : kMethods) {
    if (name == known) return name;
  }
  return "METHOD_UNSPECIFIED";
}

}  // namespace

const char* AnalysisStateName(AnalysisState state) {
  switch (state) {
    case AnalysisState::kQueued: return "QUEUED";
    case AnalysisState::kRunning: return "RUNNING";
    case AnalysisState::kSucceeded: return "SUCCEEDED";
    case AnalysisState::kFailed: return "FAILED";
    case AnalysisState::kCancelled: return "CANCELLED";
    case AnalysisState::kUnspecified: break;
  }
  return "STATE_UNSPECIFIED";
}

ReportFindings FindingsOfRows(const ReportRows& rows) {
  ReportFindings out;
  out.verdict = rows.verdict;
  for (const IdentifiedParameterRow& p : rows.identified) {
    IdentifiedFinding f;
    f.name = p.name;
    f.value = p.value;
    f.std_error = p.std_error;
    f.method = MethodNameOf(p.method);
    out.identified.push_back(std::move(f));
  }
  for (const EffectCandidateRow& c : rows.effect_candidates) {
    CandidateFinding f;
    f.name = c.name;
    f.estimate = c.estimate;
    f.std_error = c.std_error;
    f.unit = c.unit;
    f.statistic = c.statistic;
    f.degrees_of_freedom = c.degrees_of_freedom;
    f.p_value = c.p_value;
    f.p_value_holm = c.p_value_holm;
    f.source = c.source;
    f.identifiable = c.identifiable;
    out.candidates.push_back(std::move(f));
  }
  return out;
}

absl::StatusOr<ReportFindings> ReportFindingsOf(const StoredReport& report, const ReportDecoder& decode) {
  if (report.encoded.has_value()) return decode(*report.encoded);
  return FindingsOfRows(report.rows);
}

namespace internal {
namespace {

double Finite(double v) { return std::isfinite(v) ? v : 0.0; }

absl::Status WriteCandidates(Connection& db, const std::string& id, const std::vector<EffectCandidateRow>& candidates,
                             bool per_family) {
  for (const EffectCandidateRow& c : candidates) {
    auto done = db.Exec(
        "INSERT INTO effect_candidates (analysis_id, name, family, per_family, source, statistic, "
        "degrees_of_freedom, p_value, p_value_holm, estimate, std_error, unit, identifiable, predicted_delta_aic) "
        "VALUES ($1::uuid, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12, $13, $14) ON CONFLICT DO NOTHING",
        {Param::Text(id), Param::Text(c.name), Param::Text(c.family), Param::Text(per_family ? "true" : "false"),
         Param::Text(c.source), Param::Double(Finite(c.statistic)), Param::Int(c.degrees_of_freedom),
         Param::Double(Finite(c.p_value)), Param::Double(Finite(c.p_value_holm)), Param::Double(Finite(c.estimate)),
         Param::Double(Finite(c.std_error)), Param::Text(c.unit), Param::Text(c.identifiable ? "true" : "false"),
         Param::Double(Finite(c.predicted_delta_aic))});
    if (!done.ok()) return done.status();
  }
  return absl::OkStatus();
}

absl::Status ReadCandidates(Connection& db, const std::string& analysis_id, ReportRows& report) {
  INSDIAG_ASSIGN_OR_RETURN(auto rows,
                           db.Exec("SELECT name, family, source, statistic, degrees_of_freedom, "
                                   "p_value, p_value_holm, estimate, "
                                   "coalesce(std_error, 0), unit, identifiable, "
                                   "coalesce(predicted_delta_aic, 0), per_family "
                                   "FROM effect_candidates WHERE analysis_id = $1::uuid ORDER BY "
                                   "per_family, p_value_holm, name",
                                   {Param::Text(analysis_id)}));
  for (int r = 0; r < rows.rows(); ++r) {
    EffectCandidateRow c;
    c.name = rows.String(r, 0);
    c.family = rows.String(r, 1);
    c.source = rows.String(r, 2);
    c.statistic = DoubleOr0(rows, r, 3);
    c.degrees_of_freedom = static_cast<int>(IntOr0(rows, r, 4));
    c.p_value = DoubleOr0(rows, r, 5);
    c.p_value_holm = DoubleOr0(rows, r, 6);
    c.estimate = DoubleOr0(rows, r, 7);
    c.std_error = DoubleOr0(rows, r, 8);
    c.unit = rows.String(r, 9);
    c.identifiable = rows.Bool(r, 10);
    c.predicted_delta_aic = DoubleOr0(rows, r, 11);
    (rows.Bool(r, 12) ? report.family_candidates : report.effect_candidates).push_back(std::move(c));
  }
  return absl::OkStatus();
}

absl::Status ReadIdentified(Connection& db, const std::string& analysis_id, ReportRows& report) {
  INSDIAG_ASSIGN_OR_RETURN(auto rows, db.Exec("SELECT n.name, p.value, coalesce(p.std_error, 0), "
                                              "p.method, p.a_priori FROM identified_parameters p "
                                              "JOIN parameter_names n USING (parameter_id) WHERE "
                                              "p.analysis_id = $1::uuid ORDER BY n.name",
                                              {Param::Text(analysis_id)}));
  for (int r = 0; r < rows.rows(); ++r) {
    IdentifiedParameterRow p;
    p.name = rows.String(r, 0);
    p.value = DoubleOr0(rows, r, 1);
    p.std_error = DoubleOr0(rows, r, 2);
    p.method = rows.String(r, 3);
    p.a_priori = rows.OptionalDouble(r, 4);
    report.identified.push_back(std::move(p));
  }
  return absl::OkStatus();
}

absl::Status ReadChannelsAndIntervals(Connection& db, const std::string& analysis_id, ReportRows& report) {
  INSDIAG_ASSIGN_OR_RETURN(
      auto channels,
      db.Exec("SELECT channel, rms, fit_percent, nis_mean, whiteness_p_value, sample_count FROM "
              "channel_metrics "
              "WHERE analysis_id = $1::uuid ORDER BY CASE channel WHEN 'lat' THEN 0 WHEN 'lon' "
              "THEN 1 WHEN 'height' THEN 2 "
              "WHEN 'vel_n' THEN 3 WHEN 'vel_e' THEN 4 WHEN 'vel_d' THEN 5 ELSE 6 END, channel",
              {Param::Text(analysis_id)}));
  for (int r = 0; r < channels.rows(); ++r) {
    ChannelMetricRow c;
    c.channel = channels.String(r, 0);
    c.rms = DoubleOr0(channels, r, 1);
    c.fit_percent = DoubleOr0(channels, r, 2);
    c.nis_mean = DoubleOr0(channels, r, 3);
    c.whiteness_p_value = DoubleOr0(channels, r, 4);
    c.sample_count = IntOr0(channels, r, 5);
    report.channels.push_back(std::move(c));
  }
  INSDIAG_ASSIGN_OR_RETURN(auto intervals,
                           db.Exec("SELECT channel, start_s, end_s, kind, peak_statistic FROM "
                                   "fault_intervals WHERE analysis_id = $1::uuid "
                                   "ORDER BY position",
                                   {Param::Text(analysis_id)}));
  for (int r = 0; r < intervals.rows(); ++r) {
    FaultIntervalRow f;
    f.channel = intervals.String(r, 0);
    f.start_s = DoubleOr0(intervals, r, 1);
    f.end_s = DoubleOr0(intervals, r, 2);
    f.kind = FaultKindNamed(intervals.String(r, 3));
    f.peak_statistic = DoubleOr0(intervals, r, 4);
    report.fault_intervals.push_back(std::move(f));
  }
  return absl::OkStatus();
}

}  // namespace

absl::Status WriteReportRows(Connection& db, const std::string& id, const ReportRows& report) {
  for (const ChannelMetricRow& c : report.channels) {
    auto done = db.Exec(
        "INSERT INTO channel_metrics (analysis_id, channel, rms, fit_percent, nis_mean, whiteness_p_value, "
        "sample_count) VALUES ($1::uuid, $2, $3, $4, $5, $6, $7)",
        {Param::Text(id), Param::Text(c.channel), Param::Double(Finite(c.rms)), Param::Double(Finite(c.fit_percent)),
         Param::Double(Finite(c.nis_mean)), Param::Double(Finite(c.whiteness_p_value)), Param::Int(c.sample_count)});
    if (!done.ok()) return done.status();
  }
  for (const IdentifiedParameterRow& p : report.identified) {
    auto done = db.Exec(
        "WITH n AS (INSERT INTO parameter_names (name) VALUES ($2) ON CONFLICT (name) DO UPDATE SET name = EXCLUDED.name "
        "RETURNING parameter_id) "
        "INSERT INTO identified_parameters (analysis_id, parameter_id, value, std_error, method, a_priori) "
        "SELECT $1::uuid, parameter_id, $3, $4, $5, $6 FROM n ON CONFLICT DO NOTHING",
        {Param::Text(id), Param::Text(p.name), Param::Double(p.value), Param::Double(p.std_error),
         Param::Text(p.method), p.a_priori.has_value() ? Param::Double(*p.a_priori) : Param::Null()});
    if (!done.ok()) return done.status();
  }
  INSDIAG_RETURN_IF_ERROR(WriteCandidates(db, id, report.effect_candidates, false));
  INSDIAG_RETURN_IF_ERROR(WriteCandidates(db, id, report.family_candidates, true));
  int position = 0;
  for (const FaultIntervalRow& f : report.fault_intervals) {
    auto done = db.Exec(
        "INSERT INTO fault_intervals (analysis_id, position, channel, start_s, end_s, kind, peak_statistic) "
        "VALUES ($1::uuid, $2, $3, $4, $5, $6, $7)",
        {Param::Text(id), Param::Int(position++), Param::Text(f.channel), Param::Double(f.start_s),
         Param::Double(f.end_s), Param::Text(f.kind.has_value() ? engine::FaultKindName(*f.kind) : "UNSPECIFIED"),
         Param::Double(Finite(f.peak_statistic))});
    if (!done.ok()) return done.status();
  }
  return absl::OkStatus();
}

absl::StatusOr<ReportRows> ReadReportRows(Connection& db, const std::string& analysis_id) {
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows,
      db.Exec("SELECT coalesce(verdict, ''), nis_mean, log_likelihood, aic, bic FROM analyses "
              "WHERE analysis_id = $1::uuid",
              {Param::Text(analysis_id)}, ResultFormat::kBinary));
  if (rows.rows() == 0)
    return absl::NotFoundError(
        absl::StrCat(api::ResourceName(api::kAnalyses, analysis_id), " does not exist"));
  ReportRows report;
  report.verdict = VerdictNamed(rows.Get(0, 0));
  // Binary float8: big-endian IEEE-754.
  const auto binary_double = [&](int column) {
    if (rows.IsNull(0, column)) return 0.0;
    std::uint64_t bits = 0;
    for (const char c : rows.Get(0, column)) bits = (bits << 8) | static_cast<unsigned char>(c);
    return std::bit_cast<double>(bits);
  };
  report.nis_mean = binary_double(1);
  report.log_likelihood = binary_double(2);
  report.aic = binary_double(3);
  report.bic = binary_double(4);
  INSDIAG_RETURN_IF_ERROR(ReadIdentified(db, analysis_id, report));
  INSDIAG_RETURN_IF_ERROR(ReadCandidates(db, analysis_id, report));
  INSDIAG_RETURN_IF_ERROR(ReadChannelsAndIntervals(db, analysis_id, report));
  return report;
}

absl::StatusOr<StoredReport> LoadReport(Connection& db, const std::string& analysis_id) {
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
  StoredReport report;
  if (rows.IsNull(0, 1)) {
    INSDIAG_ASSIGN_OR_RETURN(report.rows, ReadReportRows(db, analysis_id));
  } else {
    report.encoded = std::string(rows.Get(0, 1));
  }
  return report;
}

}  // namespace internal
}  // namespace insdiag::kb
