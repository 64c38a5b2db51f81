#include "insdiag/kb/fleet_store.h"

#include <absl/strings/match.h>
#include <absl/strings/str_cat.h>
#include <absl/time/time.h>

#include <cmath>
#include <optional>
#include <vector>

#include "insdiag/api/resource_names.h"
#include "insdiag/engine/status_macros.h"
#include "insdiag/kb/reliability.h"
#include "store_util.h"

namespace insdiag::kb {
namespace {

using internal::Micros;

absl::StatusOr<std::string> UnitTypeFilter(const std::string& unit_type) {
  if (unit_type.empty()) return std::string();
  return api::ResourceId(unit_type, api::kUnitTypes, "unit_type");
}

double Confidence(double requested) { return requested > 0.0 && requested < 1.0 ? requested : 0.90; }

absl::StatusOr<std::string> ModeFilter(const std::string& failure_mode) {
  if (failure_mode.empty()) return std::string();
  return api::ResourceId(failure_mode, api::kFailureModes, "failure_mode");
}

constexpr double kSecondsPerYear = 365.25 * 86400.0;

Param TimeOrNull(const std::optional<absl::Time>& time) {
  return time.has_value() ? Param::Text(internal::TimeText(*time)) : Param::Null();
}

}  // namespace

absl::StatusOr<FleetStatistics> FleetStore::GetFleetStatistics(const FleetStatisticsQuery& query) {
  INSDIAG_ASSIGN_OR_RETURN(auto type, UnitTypeFilter(query.unit_type));
  if (query.confidence < 0 || query.confidence >= 1) {
    return absl::InvalidArgumentError("confidence must be within (0, 1) (0: the default 0.90)");
  }
  const double confidence = Confidence(query.confidence);
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  FleetStatistics out;
  out.unit_type = query.unit_type;
  out.confidence = confidence;
  INSDIAG_ASSIGN_OR_RETURN(
      auto counts, db->Exec("SELECT coalesce(sum(units), 0)::bigint, coalesce(sum(runs), "
                            "0)::bigint, coalesce(sum(analyses), 0)::bigint, " +
                                Micros("min(refreshed_time)") +
                                " FROM fleet_counts WHERE $1::text IS NULL OR unit_type = $1",
                            {Param::TextOrNull(type)}));
  out.unit_count = internal::IntOr0(counts, 0, 0);
  out.run_count = internal::IntOr0(counts, 0, 1);
  out.analysis_count = internal::IntOr0(counts, 0, 2);
  if (!counts.IsNull(0, 3)) out.counts_time = absl::FromUnixMicros(internal::IntOr0(counts, 0, 3));
  // Exposure of each role (every installed part from installation to removal
  // or to its unit's present hours) from the materialised module_exposure,
  // as of counts_time; failures live from the records.
  auto rows = db->Exec(
      "WITH m AS (SELECT role, sum(modules)::bigint AS modules, sum(hours) AS hours FROM "
      "module_exposure "
      "  WHERE $1::text IS NULL OR unit_type = $1 GROUP BY role), "
      "f AS (SELECT m.role, count(*) FILTER (WHERE r.confirmed) AS failures, "
      "  count(*) FILTER (WHERE r.no_fault_found) AS nff FROM failure_records r JOIN modules m "
      "USING (module_id) "
      "  WHERE (r.confirmed OR r.no_fault_found) "
      "  AND ($1::text IS NULL OR r.unit_id IN (SELECT unit_id FROM units WHERE unit_type = $1)) "
      "GROUP BY m.role) "
      "SELECT role, coalesce(m.modules, 0), coalesce(m.hours, 0), coalesce(f.failures, 0), "
      "coalesce(f.nff, 0) "
      "FROM m FULL JOIN f USING (role) ORDER BY role",
      {Param::TextOrNull(type)});
  if (!rows.ok()) return rows.status();
  out.failure_rates.reserve(static_cast<std::size_t>(rows->rows()));
  for (int r = 0; r < rows->rows(); ++r) {
    ModuleFailureRate& rate = out.failure_rates.emplace_back();
    rate.module_role = rows->String(r, 0);
    rate.modules = internal::IntOr0(*rows, r, 1);
    const double hours = internal::DoubleOr0(*rows, r, 2);
    const std::int64_t failures = internal::IntOr0(*rows, r, 3);
    rate.operating_hours = hours;
    rate.failures = failures;
    rate.no_fault_found = internal::IntOr0(*rows, r, 4);
    rate.failures_per_million_hours = hours > 0 ? 1e6 * static_cast<double>(failures) / hours : 0.0;
    const MtbfEstimate mtbf = EstimateMtbf(hours, failures, confidence);
    rate.mtbf_hours = mtbf.mtbf_hours;
    rate.mtbf_lower_hours = mtbf.lower_hours;
    rate.mtbf_upper_hours = mtbf.upper_hours;
    out.failure_count += failures;
    out.no_fault_found_count += rate.no_fault_found;
  }
  return out;
}

absl::StatusOr<FailureCounts> FleetStore::ListFailureCounts(const FailureCountQuery& query) {
  INSDIAG_ASSIGN_OR_RETURN(auto type, UnitTypeFilter(query.unit_type));
  INSDIAG_ASSIGN_OR_RETURN(auto mode, ModeFilter(query.failure_mode));
  const std::string period = query.period.empty() ? "month" : query.period;
  if (period != "month" && period != "quarter" && period != "year") {
    return absl::InvalidArgumentError(absl::StrCat("period: '", query.period, "' is not month, quarter or year"));
  }
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  auto rows = db->Exec(
      "SELECT r.failure_mode, f.module_role, coalesce(u.unit_type, ''), coalesce(u.batch, ''), " +
          Micros("date_trunc($2, r.detected_time AT TIME ZONE 'UTC') AT TIME ZONE 'UTC'") +
          ", count(*) FROM failure_records r JOIN failure_modes f USING (failure_mode) "
          "JOIN units u ON u.unit_id = r.unit_id WHERE r.confirmed AND ($1::text IS NULL OR "
          "u.unit_type = $1) "
          "AND ($3::text IS NULL OR r.failure_mode = $3) AND ($4::text IS NULL OR u.batch = $4) "
          "AND ($5::timestamptz IS NULL OR r.detected_time >= $5) AND ($6::timestamptz IS NULL OR "
          "r.detected_time < $6) "
          "GROUP BY 1, 2, 3, 4, 5 ORDER BY 5, 1, 3, 4",
      {Param::TextOrNull(type), Param::Text(period), Param::TextOrNull(mode),
       Param::TextOrNull(query.batch), TimeOrNull(query.start_time), TimeOrNull(query.end_time)});
  if (!rows.ok()) return rows.status();
  FailureCounts out;
  out.counts.reserve(static_cast<std::size_t>(rows->rows()));
  for (int r = 0; r < rows->rows(); ++r) {
    FailureCount& count = out.counts.emplace_back();
    count.failure_mode = api::ResourceName(api::kFailureModes, rows->String(r, 0));
    count.module_role = rows->String(r, 1);
    if (!rows->String(r, 2).empty()) count.unit_type = api::ResourceName(api::kUnitTypes, rows->String(r, 2));
    count.batch = rows->String(r, 3);
    count.period_start = absl::FromUnixMicros(internal::IntOr0(*rows, r, 4));
    count.failures = internal::IntOr0(*rows, r, 5);
    out.total += count.failures;
  }
  return out;
}

absl::StatusOr<FailurePareto> FleetStore::GetFailurePareto(const FailureParetoQuery& query) {
  INSDIAG_ASSIGN_OR_RETURN(auto type, UnitTypeFilter(query.unit_type));
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows,
      db->Exec(
          "SELECT f.failure_mode, f.module_role, f.display_name, count(r.record_id) FROM "
          "failure_modes f "
          "LEFT JOIN failure_records r ON r.failure_mode = f.failure_mode AND r.confirmed "
          "AND ($1::text IS NULL OR r.unit_id IN (SELECT unit_id FROM units WHERE unit_type = $1)) "
          "WHERE $1::text IS NULL OR f.unit_type = $1 GROUP BY 1, 2, 3 ORDER BY 4 DESC, 1",
          {Param::TextOrNull(type)}));
  FailurePareto out;
  out.unit_type = query.unit_type;
  std::int64_t total = 0;
  for (int r = 0; r < rows.rows(); ++r) total += internal::IntOr0(rows, r, 3);
  out.total_failures = total;
  double cumulative = 0.0;
  out.entries.reserve(static_cast<std::size_t>(rows.rows()));
  for (int r = 0; r < rows.rows(); ++r) {
    ParetoEntry& entry = out.entries.emplace_back();
    entry.failure_mode = api::ResourceName(api::kFailureModes, rows.String(r, 0));
    entry.module_role = rows.String(r, 1);
    entry.display_name = rows.String(r, 2);
    entry.failures = internal::IntOr0(rows, r, 3);
    const double share = total > 0 ? static_cast<double>(entry.failures) / static_cast<double>(total) : 0.0;
    cumulative += share;
    entry.share = share;
    entry.cumulative_share = cumulative;
  }
  return out;
}

absl::StatusOr<WeibullFit> FleetStore::GetWeibullFit(const WeibullFitQuery& query) {
  INSDIAG_ASSIGN_OR_RETURN(auto type, UnitTypeFilter(query.unit_type));
  INSDIAG_ASSIGN_OR_RETURN(auto mode, ModeFilter(query.failure_mode));
  if (query.module_role.empty()) return absl::InvalidArgumentError("module_role: required, e.g. gyro.x");
  if (query.confidence < 0 || query.confidence >= 1) {
    return absl::InvalidArgumentError("confidence must be within (0, 1) (0: the default 0.90)");
  }
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  // Every installed part of the role is one life: failed (by the mode, when
  // given) at its first confirmed failure, else censored at its removal or at
  // the unit's present hours (competing risks: other modes censor).
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows,
      db->Exec(
          "SELECT coalesce(fr.hours, m.removed_hours, u.operating_hours) - m.installed_hours, "
          "fr.hours IS NOT NULL "
          "FROM modules m JOIN units u USING (unit_id) "
          "LEFT JOIN LATERAL (SELECT min(r.operating_hours) AS hours FROM failure_records r WHERE "
          "r.module_id = "
          "m.module_id AND r.confirmed AND ($3::text IS NULL OR r.failure_mode = $3)) fr ON true "
          "WHERE m.role = $2 AND ($1::text IS NULL OR u.unit_type = $1)",
          {Param::TextOrNull(type), Param::Text(query.module_role), Param::TextOrNull(mode)}));
  std::vector<LifeObservation> lives;
  lives.reserve(static_cast<std::size_t>(rows.rows()));
  for (int r = 0; r < rows.rows(); ++r) {
    const double hours = internal::DoubleOr0(rows, r, 0);
    if (hours > 0.0) lives.push_back({hours, rows.Bool(r, 1)});
  }
  INSDIAG_ASSIGN_OR_RETURN(auto estimate, FitWeibull(lives, Confidence(query.confidence)));
  WeibullFit out;
  out.unit_type = query.unit_type;
  out.module_role = query.module_role;
  out.failure_mode = query.failure_mode;
  out.confidence = Confidence(query.confidence);
  out.estimate = estimate;
  return out;
}

absl::StatusOr<ParameterPointPage> FleetStore::ListParameterTrends(const ParameterPointQuery& query) {
  INSDIAG_ASSIGN_OR_RETURN(auto type, UnitTypeFilter(query.unit_type));
  if (query.parameter.empty()) return absl::InvalidArgumentError("parameter: required, e.g. gyro_bias_gm.x.sigma");
  std::string serial;
  if (!query.unit.empty()) {
    INSDIAG_ASSIGN_OR_RETURN(auto s, api::ResourceId(query.unit, api::kUnits, "unit"));
    serial = s;
  }
  const int size = internal::ClampPageSize(query.page.page_size);
  std::vector<Param> params = {Param::Int(size + 1), Param::TextOrNull(type),
                               Param::Text(query.parameter), Param::TextOrNull(serial)};
  INSDIAG_ASSIGN_OR_RETURN(
      auto after, internal::KeysetCondition(query.page.page_token, "a.create_time", "a.analysis_id",
                                            internal::KeysetOrder::kOldestFirst, params));
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  auto rows = db->Exec(
      absl::StrCat(
          "SELECT u.serial, a.analysis_id::text, coalesce(a.unit_hours, 0), p.value, "
          "coalesce(p.std_error, 0), ",
          Micros("a.create_time"),
          ", a.create_time::text FROM identified_parameters p JOIN analyses a USING (analysis_id) "
          "JOIN units u ON u.unit_id = a.unit_id "
          "WHERE p.parameter_id = (SELECT parameter_id FROM parameter_names WHERE name = $3) "
          "AND ($2::text IS NULL OR u.unit_type = $2) AND ($4::text IS NULL OR u.serial = $4) AND ",
          after, " ORDER BY a.create_time, a.analysis_id LIMIT $1"),
      params);
  if (!rows.ok()) return rows.status();
  ParameterPointPage out;
  const int shown = std::min(rows->rows(), size);
  out.points.reserve(static_cast<std::size_t>(shown));
  for (int r = 0; r < shown; ++r) {
    ParameterPoint& point = out.points.emplace_back();
    point.unit = api::ResourceName(api::kUnits, rows->String(r, 0));
    point.analysis = api::ResourceName(api::kAnalyses, rows->String(r, 1));
    point.operating_hours = internal::DoubleOr0(*rows, r, 2);
    point.value = internal::DoubleOr0(*rows, r, 3);
    point.std_error = internal::DoubleOr0(*rows, r, 4);
    point.time = absl::FromUnixMicros(internal::IntOr0(*rows, r, 5));
  }
  if (rows->rows() > size) {
    out.next_page_token = internal::EncodeToken(rows->String(shown - 1, 6), rows->String(shown - 1, 1));
  }
  return out;
}

absl::StatusOr<ParameterTrend> FleetStore::GetParameterTrend(const ParameterTrendQuery& query) {
  INSDIAG_ASSIGN_OR_RETURN(auto type, api::ResourceId(query.unit_type, api::kUnitTypes, "unit_type"));
  if (query.parameter.empty()) return absl::InvalidArgumentError("parameter: required, e.g. gyro_bias_gm.x.sigma");
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  ParameterTrend out;
  out.unit_type = query.unit_type;
  out.parameter = query.parameter;
  INSDIAG_ASSIGN_OR_RETURN(auto nominal,
                           db->Exec("SELECT value, tolerance, unit FROM nominal_parameters WHERE "
                                    "unit_type = $1 AND parameter = $2",
                                    {Param::Text(type), Param::Text(query.parameter)}));
  if (nominal.rows() > 0) {
    out.nominal = internal::DoubleOr0(nominal, 0, 0);
    out.tolerance = internal::DoubleOr0(nominal, 0, 1);
    out.unit = nominal.String(0, 2);
  }
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows,
      db->Exec("SELECT b.batch, " + Micros("b.month") + ", b.n, b.median, b.p25, b.p75, b.mean, " +
                   Micros("b.refreshed_time") +
                   " FROM parameter_trend_buckets b WHERE b.unit_type = $1 AND b.parameter_id = "
                   "(SELECT parameter_id FROM "
                   "parameter_names WHERE name = $2) AND ($3::text IS NULL OR b.batch = $3) ORDER "
                   "BY b.batch, b.month",
               {Param::Text(type), Param::Text(query.parameter), Param::TextOrNull(query.batch)}));
  // Count-weighted least squares of the bucket medians against time.
  double sw = 0, st = 0, sy = 0, stt = 0, sty = 0;
  out.buckets.reserve(static_cast<std::size_t>(rows.rows()));
  for (int r = 0; r < rows.rows(); ++r) {
    TrendBucket& bucket = out.buckets.emplace_back();
    bucket.batch = rows.String(r, 0);
    bucket.month = absl::FromUnixMicros(internal::IntOr0(rows, r, 1));
    bucket.count = internal::IntOr0(rows, r, 2);
    bucket.median = internal::DoubleOr0(rows, r, 3);
    bucket.p25 = internal::DoubleOr0(rows, r, 4);
    bucket.p75 = internal::DoubleOr0(rows, r, 5);
    bucket.mean = internal::DoubleOr0(rows, r, 6);
    if (r == 0) out.refreshed_time = absl::FromUnixMicros(internal::IntOr0(rows, r, 7));
    const double w = static_cast<double>(bucket.count);
    const double t = static_cast<double>(absl::ToUnixSeconds(bucket.month)) / kSecondsPerYear;
    sw += w;
    st += w * t;
    sy += w * bucket.median;
    stt += w * t * t;
    sty += w * t * bucket.median;
  }
  const double denom = sw * stt - st * st;
  if (sw > 0 && denom > 1e-12 * sw * sw) {
    out.slope_per_year = (sw * sty - st * sy) / denom;
    if (out.nominal != 0.0) out.relative_slope_per_year = out.slope_per_year / out.nominal;
  }
  return out;
}

absl::StatusOr<UnitRankingPage> FleetStore::RankUnits(const UnitRankingQuery& query) {
  INSDIAG_ASSIGN_OR_RETURN(auto type, UnitTypeFilter(query.unit_type));
  const int size = internal::ClampPageSize(query.page.page_size);
  std::vector<Param> params = {Param::Int(size + 1), Param::TextOrNull(type)};
  INSDIAG_ASSIGN_OR_RETURN(const std::string after,
                           internal::KeysetAfter(query.page.page_token,
                                                 {{"l.fault_probability", "double precision"}, {"l.serial", "text"}},
                                                 internal::KeysetOrder::kDescending, params));
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  auto rows = db->Exec(
      absl::StrCat(
          "WITH l AS (SELECT DISTINCT ON (d.unit_id) d.unit_id, u.serial, coalesce(u.unit_type, "
          "'') AS unit_type, "
          "coalesce(u.batch, '') AS batch, d.fault_probability, d.top_module, d.top_failure_mode, "
          "d.top_probability, "
          "d.diagnosis_id, u.operating_hours FROM diagnoses d JOIN units u ON u.unit_id = "
          "d.unit_id "
          "WHERE $2::text IS NULL OR u.unit_type = $2 ORDER BY d.unit_id, d.create_time DESC) "
          "SELECT l.serial, l.unit_type, l.batch, l.fault_probability, l.top_module, "
          "l.top_failure_mode, "
          "l.top_probability, l.diagnosis_id::text, l.operating_hours, l.fault_probability::text "
          "FROM l WHERE ",
          after, " ORDER BY l.fault_probability DESC, l.serial DESC LIMIT $1"),
      params);
  if (!rows.ok()) return rows.status();
  UnitRankingPage out;
  const int shown = std::min(rows->rows(), size);
  out.units.reserve(static_cast<std::size_t>(shown));
  for (int r = 0; r < shown; ++r) {
    RankedUnit& unit = out.units.emplace_back();
    unit.unit = api::ResourceName(api::kUnits, rows->String(r, 0));
    if (!rows->String(r, 1).empty()) unit.unit_type = api::ResourceName(api::kUnitTypes, rows->String(r, 1));
    unit.batch = rows->String(r, 2);
    unit.fault_probability = internal::DoubleOr0(*rows, r, 3);
    unit.top_module = rows->String(r, 4);
    unit.top_failure_mode = rows->String(r, 5);
    unit.top_probability = internal::DoubleOr0(*rows, r, 6);
    unit.diagnosis = api::ResourceName(api::kDiagnoses, rows->String(r, 7));
    unit.operating_hours = internal::DoubleOr0(*rows, r, 8);
  }
  if (rows->rows() > size) {
    out.next_page_token = internal::EncodeToken(rows->String(shown - 1, 9), rows->String(shown - 1, 0));
  }
  return out;
}

absl::StatusOr<bool> FleetStore::RefreshViews(bool concurrently) {
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  const std::int64_t key = AdvisoryLockKey("insdiag.fleet.refresh");
  INSDIAG_ASSIGN_OR_RETURN(auto locked,
                           db->Exec("SELECT pg_try_advisory_lock($1)", {Param::Int(key)}));
  if (!locked.Bool(0, 0)) return false;
  const std::string refresh = concurrently ? "REFRESH MATERIALIZED VIEW CONCURRENTLY " : "REFRESH MATERIALIZED VIEW ";
  // The trend buckets sort every identified value (18 million for a fleet of
  // a million analyses): in memory when it fits, rather than in 4 MB runs.
  absl::Status status = db->ExecScript("SET work_mem = '256MB'");
  for (const char* view : {"fleet_counts", "module_exposure", "parameter_trend_buckets"}) {
    if (status.ok()) status = db->ExecScript(refresh + view);
  }
  (void)(db)->ExecScript("RESET work_mem");
  (void)(db)->Exec("SELECT pg_advisory_unlock($1)", {Param::Int(key)});
  if (!status.ok()) return status;
  return true;
}

}  // namespace insdiag::kb
