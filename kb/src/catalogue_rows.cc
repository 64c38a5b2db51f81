#include "catalogue_rows.h"

#include <absl/strings/str_cat.h>

#include <map>
#include <optional>

#include "insdiag/api/resource_names.h"
#include "insdiag/engine/status_macros.h"
#include "insdiag/kb/diagnosis.h"
#include "store_util.h"

namespace insdiag::kb::internal {

std::string UnitTypeId(const std::string& name) {
  return api::IdOrSelf(name, api::kUnitTypes);
}

absl::StatusOr<UnitType> LoadUnitType(Connection& db, const std::string& id) {
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows, db.Exec("SELECT display_name, description FROM unit_types WHERE unit_type = $1",
                         {Param::Text(id)}));
  if (rows.rows() == 0)
    return absl::NotFoundError(
        absl::StrCat(api::ResourceName(api::kUnitTypes, id), " does not exist"));
  UnitType t;
  t.name = api::ResourceName(api::kUnitTypes, id);
  t.display_name = rows.String(0, 0);
  t.description = rows.String(0, 1);
  INSDIAG_ASSIGN_OR_RETURN(auto nominal,
                           db.Exec("SELECT parameter, value, tolerance, unit FROM "
                                   "nominal_parameters WHERE unit_type = $1 ORDER BY position",
                                   {Param::Text(id)}));
  for (int r = 0; r < nominal.rows(); ++r) {
    NominalParameter p;
    p.name = nominal.String(r, 0);
    p.value = DoubleOr0(nominal, r, 1);
    p.tolerance = DoubleOr0(nominal, r, 2);
    p.unit = nominal.String(r, 3);
    t.nominal.push_back(std::move(p));
  }
  return t;
}

absl::StatusOr<double> FleetExposure(Connection& db, const std::string& unit_type_id) {
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows, db.Exec("SELECT coalesce(sum(operating_hours), 0) FROM units WHERE unit_type = $1",
                         {Param::Text(unit_type_id)}));
  return DoubleOr0(rows, 0, 0);
}

namespace {

// The unit type's row of diagnosis_settings; nullopt when it has none.
absl::StatusOr<std::optional<DiagnosisSettings>> StoredSettings(Connection& db, const std::string& unit_type_id) {
  INSDIAG_ASSIGN_OR_RETURN(auto rows, db.Exec(absl::StrCat("SELECT ", kDiagnosisSettingsColumns,
                                                           " FROM diagnosis_settings WHERE unit_type = $1"),
                                              {Param::Text(unit_type_id)}));
  if (rows.rows() == 0) return std::nullopt;
  int column = 0;
  const auto next = [&] { return DoubleOr0(rows, 0, column++); };
  DiagnosisSettings s;
  s.healthy_tolerance_sd = next();
  s.healthy_log_ratio_fraction = next();
  s.healthy_z_sd = next();
  s.contamination = next();
  s.broad_log_ratio = next();
  s.broad_tolerance = next();
  s.broad_z = next();
  s.unknown_prior = next();
  s.minimum_exposure_hours = next();
  s.expert_pseudo_hours = next();
  s.expert_signature_weight = next();
  s.significance_level = next();
  s.incidental_contamination = next();
  s.trend_z_change = next();
  s.trend_z_spread = next();
  s.present_score_octaves = static_cast<int>(IntOr0(rows, 0, column));
  return s;
}

}  // namespace

absl::StatusOr<UnitTypeSettings> SettingsFor(Connection& db, const std::string& unit_type_id) {
  INSDIAG_ASSIGN_OR_RETURN(auto own, StoredSettings(db, unit_type_id));
  if (own) return UnitTypeSettings{*own, ""};
  INSDIAG_ASSIGN_OR_RETURN(auto fallback, StoredSettings(db, kDefaultSettingsUnitType));
  if (!fallback) {
    return absl::FailedPreconditionError(absl::StrCat(
        "unit type '", unit_type_id, "' has no built-in failure-mode catalogue, and neither has ",
        kDefaultSettingsUnitType, ", whose diagnosis settings apply then"));
  }
  return UnitTypeSettings{
      *fallback,
      absl::StrCat("unit type '", unit_type_id,
                   "' has no built-in failure-mode catalogue: diagnosed with ",
                   kDefaultSettingsUnitType,
                   "'s settings (healthy spreads, contamination, significance level)")};
}

absl::StatusOr<std::vector<FailureMode>> LoadModes(Connection& db, const std::string& unit_type_id,
                                                       const std::string& role, const std::string& only_mode) {
  INSDIAG_ASSIGN_OR_RETURN(auto rows,
                           db.Exec("SELECT f.failure_mode, f.unit_type, f.module_role, "
                                   "f.display_name, f.description, f.expert_rate_per_hour, "
                                   "f.weibull_shape, f.weibull_scale_hours, "
                                   "(SELECT count(*) FROM failure_records r WHERE r.failure_mode = "
                                   "f.failure_mode AND r.confirmed) "
                                   "FROM failure_modes f WHERE ($1::text IS NULL OR f.unit_type = "
                                   "$1) AND ($2::text IS NULL OR f.module_role = $2) "
                                   "AND ($3::text IS NULL OR f.failure_mode = $3) ORDER BY "
                                   "f.unit_type, f.module_role, f.failure_mode",
                                   {Param::TextOrNull(unit_type_id), Param::TextOrNull(role),
                                    Param::TextOrNull(only_mode)}));
  std::vector<FailureMode> modes;
  std::map<std::string, std::size_t> index;
  std::map<std::string, double> exposure;
  std::map<std::string, DiagnosisSettings> settings;
  for (int r = 0; r < rows.rows(); ++r) {
    FailureMode m;
    m.name = api::ResourceName(api::kFailureModes, rows.String(r, 0));
    const std::string type = rows.String(r, 1);
    m.unit_type = api::ResourceName(api::kUnitTypes, type);
    m.module_role = rows.String(r, 2);
    m.display_name = rows.String(r, 3);
    m.description = rows.String(r, 4);
    m.expert_rate_per_million_hours = DoubleOr0(rows, r, 5) * 1e6;
    m.weibull_shape = DoubleOr0(rows, r, 6);
    m.weibull_scale_hours = DoubleOr0(rows, r, 7);
    m.confirmed_failures = IntOr0(rows, r, 8);
    if (!exposure.contains(type)) {
      // Once per unit type: the fleet's hours, and its diagnosis settings.
      INSDIAG_ASSIGN_OR_RETURN(auto hours, FleetExposure(db, type));
      exposure[type] = hours;
      INSDIAG_ASSIGN_OR_RETURN(auto type_settings, SettingsFor(db, type));
      settings[type] = type_settings.settings;
    }
    m.rate_per_million_hours = 1e6 * ModeRatePerHour(m, m.confirmed_failures, exposure[type], settings[type]);
    index[rows.String(r, 0)] = modes.size();
    modes.push_back(std::move(m));
  }
  if (modes.empty()) return modes;
  std::vector<std::string> ids;
  for (const auto& [id, i] : index) ids.push_back(id);
  INSDIAG_ASSIGN_OR_RETURN(
      auto terms,
      db.Exec("SELECT failure_mode, parameter, direction, scale, common, fraction, expert_change, "
              "expert_spread, change, "
              "spread, confirmed_cases FROM signature_terms WHERE failure_mode = ANY($1::text[]) "
              "ORDER BY failure_mode, position",
              {Param::TextArray(ids)}));
  for (int r = 0; r < terms.rows(); ++r) {
    // The table's checks admit only the names these parse.
    Signature s;
    s.parameter = terms.String(r, 1);
    s.direction = DirectionNamed(terms.String(r, 2)).value_or(Direction::kEither);
    s.scale = ScaleNamed(terms.String(r, 3)).value_or(Scale::kTolerance);
    s.common = terms.Bool(r, 4);
    s.fraction = DoubleOr0(terms, r, 5);
    s.expert_change = DoubleOr0(terms, r, 6);
    s.expert_spread = DoubleOr0(terms, r, 7);
    s.change = DoubleOr0(terms, r, 8);
    s.spread = DoubleOr0(terms, r, 9);
    s.confirmed_cases = static_cast<int>(IntOr0(terms, r, 10));
    modes[index[terms.String(r, 0)]].signature.push_back(std::move(s));
  }
  return modes;
}

}  // namespace insdiag::kb::internal
