#include "insdiag/kb/fleet_store.h"

#include <absl/strings/match.h>
#include <absl/strings/str_cat.h>

#include <cmath>
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

}  // namespace

absl::StatusOr<v1::FleetStatistics> FleetStore::GetFleetStatistics(const v1::GetFleetStatisticsRequest& request) {
  INSDIAG_ASSIGN_OR_RETURN(auto type, UnitTypeFilter(request.unit_type()));
  if (request.confidence() < 0 || request.confidence() >= 1) {
    return absl::InvalidArgumentError("confidence must be within (0, 1) (0: the default 0.90)");
  }
  const double confidence = Confidence(request.confidence());
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  v1::FleetStatistics out;
  out.set_unit_type(request.unit_type());
  out.set_confidence(confidence);
  INSDIAG_ASSIGN_OR_RETURN(
      auto counts, db->Exec("SELECT coalesce(sum(units), 0)::bigint, coalesce(sum(runs), "
                            "0)::bigint, coalesce(sum(analyses), 0)::bigint, " +
                                Micros("min(refreshed_time)") +
                                " FROM fleet_counts WHERE $1::text IS NULL OR unit_type = $1",
                            {Param::TextOrNull(type)}));
  out.set_unit_count(internal::IntOr0(counts, 0, 0));
  out.set_run_count(internal::IntOr0(counts, 0, 1));
  out.set_analysis_count(internal::IntOr0(counts, 0, 2));
  if (!counts.IsNull(0, 3))
    *out.mutable_counts_time() = internal::TimestampOfMicros(internal::IntOr0(counts, 0, 3));
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
  for (int r = 0; r < rows->rows(); ++r) {
    auto* rate = out.add_failure_rates();
    rate->set_module_role(rows->String(r, 0));
    rate->set_modules(internal::IntOr0(*rows, r, 1));
    const double hours = internal::DoubleOr0(*rows, r, 2);
    const std::int64_t failures = internal::IntOr0(*rows, r, 3);
    rate->set_operating_hours(hours);
    rate->set_failures(failures);
    rate->set_no_fault_found(internal::IntOr0(*rows, r, 4));
    rate->set_failures_per_million_hours(hours > 0 ? 1e6 * static_cast<double>(failures) / hours : 0.0);
    const MtbfEstimate mtbf = EstimateMtbf(hours, failures, confidence);
    rate->set_mtbf_hours(mtbf.mtbf_hours);
    rate->set_mtbf_lower_hours(mtbf.lower_hours);
    rate->set_mtbf_upper_hours(mtbf.upper_hours);
    out.set_failure_count(out.failure_count() + failures);
    out.set_no_fault_found_count(out.no_fault_found_count() + rate->no_fault_found());
  }
  return out;
}

absl::StatusOr<v1::ListFailureCountsResponse> FleetStore::ListFailureCounts(
    const v1::ListFailureCountsRequest& request) {
  INSDIAG_ASSIGN_OR_RETURN(auto type, UnitTypeFilter(request.unit_type()));
  INSDIAG_ASSIGN_OR_RETURN(auto mode, ModeFilter(request.failure_mode()));
  const std::string period = request.period().empty() ? "month" : request.period();
  if (period != "month" && period != "quarter" && period != "year") {
    return absl::InvalidArgumentError(absl::StrCat("period: '", request.period(), "' is not month, quarter or year"));
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
       Param::TextOrNull(request.batch()),
       request.has_start_time() ? Param::Text(internal::TimestampText(request.start_time()))
                                : Param::Null(),
       request.has_end_time() ? Param::Text(internal::TimestampText(request.end_time()))
                              : Param::Null()});
  if (!rows.ok()) return rows.status();
  v1::ListFailureCountsResponse out;
  for (int r = 0; r < rows->rows(); ++r) {
    auto* c = out.add_counts();
    c->set_failure_mode(api::ResourceName(api::kFailureModes, rows->String(r, 0)));
    c->set_module_role(rows->String(r, 1));
    if (!rows->String(r, 2).empty())
      c->set_unit_type(api::ResourceName(api::kUnitTypes, rows->String(r, 2)));
    c->set_batch(rows->String(r, 3));
    *c->mutable_period_start() = internal::TimestampOfMicros(internal::IntOr0(*rows, r, 4));
    c->set_failures(internal::IntOr0(*rows, r, 5));
    out.set_total(out.total() + c->failures());
  }
  return out;
}

absl::StatusOr<v1::FailurePareto> FleetStore::GetFailurePareto(const v1::GetFailureParetoRequest& request) {
  INSDIAG_ASSIGN_OR_RETURN(auto type, UnitTypeFilter(request.unit_type()));
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
  v1::FailurePareto out;
  out.set_unit_type(request.unit_type());
  std::int64_t total = 0;
  for (int r = 0; r < rows.rows(); ++r) total += internal::IntOr0(rows, r, 3);
  out.set_total_failures(total);
  double cumulative = 0.0;
  for (int r = 0; r < rows.rows(); ++r) {
    auto* e = out.add_entries();
    e->set_failure_mode(api::ResourceName(api::kFailureModes, rows.String(r, 0)));
    e->set_module_role(rows.String(r, 1));
    e->set_display_name(rows.String(r, 2));
    e->set_failures(internal::IntOr0(rows, r, 3));
    const double share = total > 0 ? static_cast<double>(e->failures()) / static_cast<double>(total) : 0.0;
    cumulative += share;
    e->set_share(share);
    e->set_cumulative_share(cumulative);
  }
  return out;
}

absl::StatusOr<v1::WeibullFit> FleetStore::GetWeibullFit(const v1::GetWeibullFitRequest& request) {
  INSDIAG_ASSIGN_OR_RETURN(auto type, UnitTypeFilter(request.unit_type()));
  INSDIAG_ASSIGN_OR_RETURN(auto mode, ModeFilter(request.failure_mode()));
  if (request.module_role().empty()) return absl::InvalidArgumentError("module_role: required, e.g. gyro.x");
  if (request.confidence() < 0 || request.confidence() >= 1) {
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
          {Param::TextOrNull(type), Param::Text(request.module_role()), Param::TextOrNull(mode)}));
  std::vector<LifeObservation> lives;
  lives.reserve(static_cast<std::size_t>(rows.rows()));
  for (int r = 0; r < rows.rows(); ++r) {
    const double hours = internal::DoubleOr0(rows, r, 0);
    if (hours > 0.0) lives.push_back({hours, rows.Bool(r, 1)});
  }
  INSDIAG_ASSIGN_OR_RETURN(auto fit, FitWeibull(lives, Confidence(request.confidence())));
  v1::WeibullFit out;
  out.set_unit_type(request.unit_type());
  out.set_module_role(request.module_role());
  out.set_failure_mode(request.failure_mode());
  out.set_confidence(Confidence(request.confidence()));
  out.set_failures(fit.failures);
  out.set_suspensions(fit.suspensions);
  out.set_shape(fit.shape);
  out.set_scale_hours(fit.scale_hours);
  out.set_shape_std_error(fit.shape_std_error);
  out.set_scale_std_error_hours(fit.scale_std_error_hours);
  out.set_shape_lower(fit.shape_lower);
  out.set_shape_upper(fit.shape_upper);
  out.set_scale_lower_hours(fit.scale_lower_hours);
  out.set_scale_upper_hours(fit.scale_upper_hours);
  out.set_b10_hours(fit.b10_hours);
  out.set_b10_lower_hours(fit.b10_lower_hours);
  out.set_b10_upper_hours(fit.b10_upper_hours);
  out.set_log_likelihood(fit.log_likelihood);
  return out;
}

absl::StatusOr<v1::ListParameterTrendsResponse> FleetStore::ListParameterTrends(
    const v1::ListParameterTrendsRequest& request) {
  INSDIAG_ASSIGN_OR_RETURN(auto type, UnitTypeFilter(request.unit_type()));
  if (request.parameter().empty()) return absl::InvalidArgumentError("parameter: required, e.g. gyro_bias_gm.x.sigma");
  std::string serial;
  if (!request.unit().empty()) {
    INSDIAG_ASSIGN_OR_RETURN(auto s, api::ResourceId(request.unit(), api::kUnits, "unit"));
    serial = s;
  }
  const int size = internal::ClampPageSize(request.page_size());
  std::vector<Param> params = {Param::Int(size + 1), Param::TextOrNull(type),
                               Param::Text(request.parameter()), Param::TextOrNull(serial)};
  INSDIAG_ASSIGN_OR_RETURN(
      auto after, internal::KeysetCondition(request.page_token(), "a.create_time", "a.analysis_id",
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
  v1::ListParameterTrendsResponse out;
  const int shown = std::min(rows->rows(), size);
  for (int r = 0; r < shown; ++r) {
    auto* p = out.add_points();
    p->set_unit(api::ResourceName(api::kUnits, rows->String(r, 0)));
    p->set_analysis(api::ResourceName(api::kAnalyses, rows->String(r, 1)));
    p->set_operating_hours(internal::DoubleOr0(*rows, r, 2));
    p->set_value(internal::DoubleOr0(*rows, r, 3));
    p->set_std_error(internal::DoubleOr0(*rows, r, 4));
    *p->mutable_time() = internal::TimestampOfMicros(internal::IntOr0(*rows, r, 5));
  }
  if (rows->rows() > size) out.set_next_page_token(internal::EncodeToken(rows->String(shown - 1, 6), rows->String(shown - 1, 1)));
  return out;
}

absl::StatusOr<v1::ParameterTrend> FleetStore::GetParameterTrend(const v1::GetParameterTrendRequest& request) {
  INSDIAG_ASSIGN_OR_RETURN(auto type,
                           api::ResourceId(request.unit_type(), api::kUnitTypes, "unit_type"));
  if (request.parameter().empty()) return absl::InvalidArgumentError("parameter: required, e.g. gyro_bias_gm.x.sigma");
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  v1::ParameterTrend out;
  out.set_unit_type(request.unit_type());
  out.set_parameter(request.parameter());
  INSDIAG_ASSIGN_OR_RETURN(auto nominal,
                           db->Exec("SELECT value, tolerance, unit FROM nominal_parameters WHERE "
                                    "unit_type = $1 AND parameter = $2",
                                    {Param::Text(type), Param::Text(request.parameter())}));
  if (nominal.rows() > 0) {
    out.set_nominal(internal::DoubleOr0(nominal, 0, 0));
    out.set_tolerance(internal::DoubleOr0(nominal, 0, 1));
    out.set_unit(nominal.String(0, 2));
  }
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows,
      db->Exec("SELECT b.batch, " + Micros("b.month") + ", b.n, b.median, b.p25, b.p75, b.mean, " +
                   Micros("b.refreshed_time") +
                   " FROM parameter_trend_buckets b WHERE b.unit_type = $1 AND b.parameter_id = "
                   "(SELECT parameter_id FROM "
                   "parameter_names WHERE name = $2) AND ($3::text IS NULL OR b.batch = $3) ORDER "
                   "BY b.batch, b.month",
               {Param::Text(type), Param::Text(request.parameter()),
                Param::TextOrNull(request.batch())}));
  // Count-weighted least squares of the bucket medians against time.
  double sw = 0, st = 0, sy = 0, stt = 0, sty = 0;
  for (int r = 0; r < rows.rows(); ++r) {
    auto* b = out.add_buckets();
    b->set_batch(rows.String(r, 0));
    *b->mutable_month() = internal::TimestampOfMicros(internal::IntOr0(rows, r, 1));
    b->set_count(internal::IntOr0(rows, r, 2));
    b->set_median(internal::DoubleOr0(rows, r, 3));
    b->set_p25(internal::DoubleOr0(rows, r, 4));
    b->set_p75(internal::DoubleOr0(rows, r, 5));
    b->set_mean(internal::DoubleOr0(rows, r, 6));
    if (r == 0)
      *out.mutable_refreshed_time() = internal::TimestampOfMicros(internal::IntOr0(rows, r, 7));
    const double w = static_cast<double>(b->count());
    const double t = static_cast<double>(b->month().seconds()) / kSecondsPerYear;
    sw += w;
    st += w * t;
    sy += w * b->median();
    stt += w * t * t;
    sty += w * t * b->median();
  }
  const double denom = sw * stt - st * st;
  if (sw > 0 && denom > 1e-12 * sw * sw) {
    out.set_slope_per_year((sw * sty - st * sy) / denom);
    if (out.nominal() != 0.0) out.set_relative_slope_per_year(out.slope_per_year() / out.nominal());
  }
  return out;
}

absl::StatusOr<v1::RankUnitsResponse> FleetStore::RankUnits(const v1::RankUnitsRequest& request) {
  INSDIAG_ASSIGN_OR_RETURN(auto type, UnitTypeFilter(request.unit_type()));
  const int size = internal::ClampPageSize(request.page_size());
  std::vector<Param> params = {Param::Int(size + 1), Param::TextOrNull(type)};
  INSDIAG_ASSIGN_OR_RETURN(const std::string after,
                           internal::KeysetAfter(request.page_token(),
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
  v1::RankUnitsResponse out;
  const int shown = std::min(rows->rows(), size);
  for (int r = 0; r < shown; ++r) {
    auto* u = out.add_units();
    u->set_unit(api::ResourceName(api::kUnits, rows->String(r, 0)));
    if (!rows->String(r, 1).empty())
      u->set_unit_type(api::ResourceName(api::kUnitTypes, rows->String(r, 1)));
    u->set_batch(rows->String(r, 2));
    u->set_fault_probability(internal::DoubleOr0(*rows, r, 3));
    u->set_top_module(rows->String(r, 4));
    u->set_top_failure_mode(rows->String(r, 5));
    u->set_top_probability(internal::DoubleOr0(*rows, r, 6));
    u->set_diagnosis(api::ResourceName(api::kDiagnoses, rows->String(r, 7)));
    u->set_operating_hours(internal::DoubleOr0(*rows, r, 8));
  }
  if (rows->rows() > size) out.set_next_page_token(internal::EncodeToken(rows->String(shown - 1, 9), rows->String(shown - 1, 0)));
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
