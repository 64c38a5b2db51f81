#include "catalogue_rows.h"

#include <absl/strings/str_cat.h>

#include <map>

#include "insdiag/api/resource_names.h"
#include "insdiag/engine/status_macros.h"
#include "insdiag/kb/diagnosis.h"
#include "store_util.h"

namespace insdiag::kb::internal {

std::string UnitTypeId(const std::string& name) {
  return api::IdOrSelf(name, api::kUnitTypes);
}

absl::StatusOr<v1::UnitType> LoadUnitType(Connection& db, const std::string& id) {
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows, db.Exec("SELECT display_name, description FROM unit_types WHERE unit_type = $1",
                         {Param::Text(id)}));
  if (rows.rows() == 0)
    return absl::NotFoundError(
        absl::StrCat(api::ResourceName(api::kUnitTypes, id), " does not exist"));
  v1::UnitType t;
  t.set_name(api::ResourceName(api::kUnitTypes, id));
  t.set_display_name(rows.String(0, 0));
  t.set_description(rows.String(0, 1));
  INSDIAG_ASSIGN_OR_RETURN(auto nominal,
                           db.Exec("SELECT parameter, value, tolerance, unit FROM "
                                   "nominal_parameters WHERE unit_type = $1 ORDER BY position",
                                   {Param::Text(id)}));
  for (int r = 0; r < nominal.rows(); ++r) {
    auto* p = t.add_nominal();
    p->set_name(nominal.String(r, 0));
    p->set_value(DoubleOr0(nominal, r, 1));
    p->set_tolerance(DoubleOr0(nominal, r, 2));
    p->set_unit(nominal.String(r, 3));
  }
  return t;
}

absl::StatusOr<double> FleetExposure(Connection& db, const std::string& unit_type_id) {
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows, db.Exec("SELECT coalesce(sum(operating_hours), 0) FROM units WHERE unit_type = $1",
                         {Param::Text(unit_type_id)}));
  return DoubleOr0(rows, 0, 0);
}

absl::StatusOr<UnitTypeSettings> SettingsFor(const std::string& unit_type_id) {
  if (auto own = BuiltinFailureModeCatalogue(unit_type_id); own.ok())
    return UnitTypeSettings{(*own)->settings(), ""};
  auto fallback = BuiltinFailureModeCatalogue(kDefaultSettingsUnitType);
  if (!fallback.ok()) {
    return absl::FailedPreconditionError(absl::StrCat(
        "unit type '", unit_type_id, "' has no built-in failure-mode catalogue, and neither has ",
        kDefaultSettingsUnitType, ", whose diagnosis settings apply then"));
  }
  return UnitTypeSettings{
      (*fallback)->settings(),
      absl::StrCat("unit type '", unit_type_id,
                   "' has no built-in failure-mode catalogue: diagnosed with ",
                   kDefaultSettingsUnitType,
                   "'s settings (healthy spreads, contamination, significance level)")};
}

absl::StatusOr<std::vector<v1::FailureMode>> LoadModes(Connection& db, const std::string& unit_type_id,
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
  std::vector<v1::FailureMode> modes;
  std::map<std::string, std::size_t> index;
  std::map<std::string, double> exposure;
  std::map<std::string, v1::DiagnosisSettings> settings;
  for (int r = 0; r < rows.rows(); ++r) {
    v1::FailureMode m;
    m.set_name(api::ResourceName(api::kFailureModes, rows.String(r, 0)));
    const std::string type = rows.String(r, 1);
    m.set_unit_type(api::ResourceName(api::kUnitTypes, type));
    m.set_module_role(rows.String(r, 2));
    m.set_display_name(rows.String(r, 3));
    m.set_description(rows.String(r, 4));
    m.set_expert_rate_per_million_hours(DoubleOr0(rows, r, 5) * 1e6);
    m.set_weibull_shape(DoubleOr0(rows, r, 6));
    m.set_weibull_scale_hours(DoubleOr0(rows, r, 7));
    m.set_confirmed_failures(IntOr0(rows, r, 8));
    if (!exposure.contains(type)) {
      // Once per unit type: the fleet's hours, and its catalogue's settings (parsed from JSON).
      INSDIAG_ASSIGN_OR_RETURN(auto hours, FleetExposure(db, type));
      exposure[type] = hours;
      INSDIAG_ASSIGN_OR_RETURN(auto type_settings, SettingsFor(type));
      settings[type] = type_settings.settings;
    }
    m.set_rate_per_million_hours(
        1e6 * ModeRatePerHour(m, m.confirmed_failures(), exposure[type], settings[type]));
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
    auto* s = modes[index[terms.String(r, 0)]].add_signature();
    s->set_parameter(terms.String(r, 1));
    v1::Signature::Direction d = v1::Signature::EITHER;
    v1::Signature::Direction_Parse(terms.String(r, 2), &d);
    s->set_direction(d);
    s->set_scale(terms.String(r, 3));
    s->set_common(terms.Bool(r, 4));
    s->set_fraction(DoubleOr0(terms, r, 5));
    s->set_expert_change(DoubleOr0(terms, r, 6));
    s->set_expert_spread(DoubleOr0(terms, r, 7));
    s->set_change(DoubleOr0(terms, r, 8));
    s->set_spread(DoubleOr0(terms, r, 9));
    s->set_confirmed_cases(static_cast<int>(IntOr0(terms, r, 10)));
  }
  return modes;
}

}  // namespace insdiag::kb::internal
