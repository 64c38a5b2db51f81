#include "insdiag/kb/catalogue_store.h"

#include <absl/strings/str_cat.h>
#include <absl/strings/str_split.h>
#include <absl/time/time.h>

#include <algorithm>

#include "catalogue_rows.h"
#include "insdiag/api/resource_names.h"
#include "insdiag/engine/status_macros.h"
#include "store_util.h"

namespace insdiag::kb {
namespace {

using internal::BoolText;
using internal::LoadModes;
using internal::LoadUnitType;
using internal::Micros;
using internal::UnitTypeId;

// Upserts the unit type and replaces its nominal values.
absl::Status UpsertUnitType(Connection& db, const UnitType& t) {
  const std::string id = UnitTypeId(t.name);
  INSDIAG_RETURN_IF_ERROR(
      db.Exec("INSERT INTO unit_types (unit_type, display_name, description) VALUES ($1, $2, $3) "
              "ON CONFLICT (unit_type) DO UPDATE SET display_name = EXCLUDED.display_name, "
              "description = EXCLUDED.description, update_time = now()",
              {Param::Text(id), Param::Text(t.display_name), Param::Text(t.description)}));
  INSDIAG_RETURN_IF_ERROR(
      db.Exec("DELETE FROM nominal_parameters WHERE unit_type = $1", {Param::Text(id)}));
  int position = 0;
  for (const NominalParameter& p : t.nominal) {
    INSDIAG_RETURN_IF_ERROR(
        db.Exec("INSERT INTO nominal_parameters (unit_type, parameter, value, tolerance, unit, "
                "position) "
                "VALUES ($1, $2, $3, $4, $5, $6)",
                {Param::Text(id), Param::Text(p.name), Param::Double(p.value),
                 Param::Double(p.tolerance), Param::Text(p.unit), Param::Int(position++)}));
  }
  return absl::OkStatus();
}

// Upserts an expanded failure mode. Its signature terms are replaced only
// when the expert's values changed: otherwise they keep what confirmed
// cases refined.
absl::Status UpsertFailureMode(Connection& db, const FailureMode& mode) {
  const std::string id = api::IdOrSelf(mode.name, api::kFailureModes);
  auto upserted = db.Exec(
      "INSERT INTO failure_modes (failure_mode, unit_type, module_role, display_name, description, "
      "expert_rate_per_hour, weibull_shape, weibull_scale_hours) VALUES ($1, $2, $3, $4, $5, $6, $7, $8) "
      "ON CONFLICT (failure_mode) DO UPDATE SET unit_type = EXCLUDED.unit_type, module_role = "
      "EXCLUDED.module_role, display_name = EXCLUDED.display_name, description = EXCLUDED.description, "
      "expert_rate_per_hour = EXCLUDED.expert_rate_per_hour, weibull_shape = EXCLUDED.weibull_shape, "
      "weibull_scale_hours = EXCLUDED.weibull_scale_hours",
      {Param::Text(id), Param::Text(UnitTypeId(mode.unit_type)), Param::Text(mode.module_role),
       Param::Text(mode.display_name), Param::Text(mode.description),
       Param::Double(mode.expert_rate_per_million_hours * 1e-6), Param::Double(mode.weibull_shape),
       Param::Double(mode.weibull_scale_hours)});
  if (!upserted.ok()) return upserted.status();
  std::vector<std::string> wanted;
  for (const Signature& s : mode.signature) {
    wanted.push_back(absl::StrCat(s.parameter, "|", DirectionName(s.direction), "|", ScaleName(s.scale), "|",
                                  BoolText(s.common), "|", s.fraction, "|", s.expert_change, "|",
                                  s.expert_spread));
  }
  INSDIAG_ASSIGN_OR_RETURN(auto existing,
                           db.Exec("SELECT parameter || '|' || direction || '|' || scale || '|' || "
                                   "common::text || '|' || fraction::text "
                                   "|| '|' || expert_change::text || '|' || expert_spread::text "
                                   "FROM signature_terms WHERE failure_mode = $1 "
                                   "ORDER BY position",
                                   {Param::Text(id)}));
  std::vector<std::string> have;
  for (int r = 0; r < existing.rows(); ++r) have.push_back(existing.String(r, 0));
  if (have == wanted) return absl::OkStatus();
  INSDIAG_RETURN_IF_ERROR(
      db.Exec("DELETE FROM signature_terms WHERE failure_mode = $1", {Param::Text(id)}));
  int position = 0;
  for (const Signature& s : mode.signature) {
    INSDIAG_RETURN_IF_ERROR(
        db.Exec("INSERT INTO signature_terms (failure_mode, position, parameter, direction, scale, "
                "common, fraction, "
                "expert_change, expert_spread, change, spread) VALUES ($1, $2, $3, $4, $5, $6, $7, "
                "$8, $9, $8, $9)",
                {Param::Text(id), Param::Int(position++), Param::Text(s.parameter),
                 Param::Text(DirectionName(s.direction)), Param::Text(ScaleName(s.scale)),
                 Param::Text(BoolText(s.common)), Param::Double(s.fraction),
                 Param::Double(s.expert_change), Param::Double(s.expert_spread)}));
  }
  return absl::OkStatus();
}

// Upserts the unit type's diagnosis settings, in kDiagnosisSettingsColumns' order.
absl::Status UpsertDiagnosisSettings(Connection& db, const UnitTypeDiagnosisSettings& of_type) {
  const DiagnosisSettings& s = of_type.settings;
  std::vector<Param> params = {Param::Text(UnitTypeId(of_type.unit_type))};
  for (const double value : {s.healthy_tolerance_sd, s.healthy_log_ratio_fraction, s.healthy_z_sd, s.contamination,
                             s.broad_log_ratio, s.broad_tolerance, s.broad_z, s.unknown_prior,
                             s.minimum_exposure_hours, s.expert_pseudo_hours, s.expert_signature_weight,
                             s.significance_level, s.incidental_contamination, s.trend_z_change,
                             s.trend_z_spread}) {
    params.push_back(Param::Double(value));
  }
  params.push_back(Param::Int(s.present_score_octaves));
  std::string placeholders;
  std::string updates;
  for (std::size_t i = 1; i <= params.size(); ++i) absl::StrAppend(&placeholders, i > 1 ? ", $" : "$", i);
  for (absl::string_view column : absl::StrSplit(internal::kDiagnosisSettingsColumns, ", ")) {
    absl::StrAppend(&updates, column, " = EXCLUDED.", column, ", ");
  }
  return db
      .Exec(absl::StrCat("INSERT INTO diagnosis_settings (unit_type, ", internal::kDiagnosisSettingsColumns,
                         ") VALUES (", placeholders, ") ON CONFLICT (unit_type) DO UPDATE SET ", updates,
                         "update_time = now()"),
            params)
      .status();
}

constexpr char kUnitColumns[] =
    "SELECT serial, coalesce(unit_type, ''), operating_hours, (extract(epoch FROM create_time) * 1000000)::bigint, "
    "coalesce(batch, ''), (extract(epoch FROM commission_time) * 1000000)::bigint, retired_time IS NOT NULL FROM units ";

Unit UnitFromRow(const Result& rows, int r) {
  Unit u;
  u.name = api::ResourceName(api::kUnits, rows.String(r, 0));
  if (!rows.String(r, 1).empty()) u.unit_type = api::ResourceName(api::kUnitTypes, rows.String(r, 1));
  u.operating_hours = internal::DoubleOr0(rows, r, 2);
  u.create_time = absl::FromUnixMicros(internal::IntOr0(rows, r, 3));
  u.batch = rows.String(r, 4);
  if (!rows.IsNull(r, 5)) u.commission_time = absl::FromUnixMicros(internal::IntOr0(rows, r, 5));
  u.retired = rows.Bool(r, 6);
  return u;
}

}  // namespace

absl::Status CatalogueStore::Seed(std::span<const UnitType> unit_types, std::span<const FailureMode> failure_modes,
                                  std::span<const UnitTypeDiagnosisSettings> settings) {
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  return db->InTransaction([&]() -> absl::Status {
    INSDIAG_RETURN_IF_ERROR(db->Exec("SELECT pg_advisory_xact_lock($1)",
                                     {Param::Int(AdvisoryLockKey("insdiag.seed"))}));
    for (const UnitType& t : unit_types) INSDIAG_RETURN_IF_ERROR(UpsertUnitType(*db, t));
    for (const FailureMode& mode : failure_modes) INSDIAG_RETURN_IF_ERROR(UpsertFailureMode(*db, mode));
    for (const UnitTypeDiagnosisSettings& of_type : settings) {
      INSDIAG_RETURN_IF_ERROR(UpsertDiagnosisSettings(*db, of_type));
    }
    return absl::OkStatus();
  });
}

absl::StatusOr<UnitType> CatalogueStore::GetUnitType(const std::string& name) {
  INSDIAG_ASSIGN_OR_RETURN(auto id, api::ResourceId(name, api::kUnitTypes, "name"));
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  return LoadUnitType(*db, id);
}

absl::StatusOr<std::vector<UnitType>> CatalogueStore::ListUnitTypes() {
  INSDIAG_ASSIGN_OR_RETURN(auto db, list_pool_.Acquire());
  INSDIAG_ASSIGN_OR_RETURN(auto rows,
                           db->Exec("SELECT unit_type FROM unit_types ORDER BY unit_type"));
  std::vector<UnitType> out;
  for (int r = 0; r < rows.rows(); ++r) {
    INSDIAG_ASSIGN_OR_RETURN(auto t, LoadUnitType(*db, rows.String(r, 0)));
    out.push_back(std::move(t));
  }
  return out;
}

absl::StatusOr<Unit> CatalogueStore::GetUnit(const std::string& name) {
  auto serial = api::ResourceId(name, api::kUnits, "name");
  if (!serial.ok()) return serial.status();
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows, db->Exec(absl::StrCat(kUnitColumns, "WHERE serial = $1"), {Param::Text(*serial)}));
  if (rows.rows() == 0) return absl::NotFoundError(absl::StrCat(name, " does not exist"));
  return UnitFromRow(rows, 0);
}

absl::StatusOr<std::pair<std::vector<Unit>, std::string>> CatalogueStore::ListUnits(const PageQuery& page,
                                                                                     const std::string& unit_type,
                                                                                     const std::string& batch) {
  const int size = internal::ClampPageSize(page.page_size);
  std::vector<Param> params = {Param::Int(size + 1),
                               Param::TextOrNull(unit_type.empty() ? "" : UnitTypeId(unit_type)),
                               Param::TextOrNull(batch)};
  INSDIAG_ASSIGN_OR_RETURN(
      const std::string after,
      internal::KeysetAfter(page.page_token, {{"serial", "text"}}, internal::KeysetOrder::kAscending, params));
  INSDIAG_ASSIGN_OR_RETURN(auto db, list_pool_.Acquire());
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows,
      db->Exec(absl::StrCat(kUnitColumns,
                            "WHERE ($2::text IS NULL OR unit_type = $2) AND ($3::text IS NULL OR batch = $3) AND ",
                            after, " ORDER BY serial LIMIT $1"),
               params));
  std::vector<Unit> units;
  const int shown = std::min(rows.rows(), size);
  for (int r = 0; r < shown; ++r) units.push_back(UnitFromRow(rows, r));
  std::string next;
  if (rows.rows() > size) next = internal::EncodeToken("", rows.String(shown - 1, 0));
  return std::make_pair(std::move(units), next);
}

absl::StatusOr<std::vector<Module>> CatalogueStore::ListModules(const std::string& unit_name) {
  auto serial = api::ResourceId(unit_name, api::kUnits, "parent");
  if (!serial.ok()) return serial.status();
  INSDIAG_ASSIGN_OR_RETURN(auto db, list_pool_.Acquire());
  INSDIAG_ASSIGN_OR_RETURN(
      auto unit, db->Exec("SELECT unit_id FROM units WHERE serial = $1", {Param::Text(*serial)}));
  if (unit.rows() == 0) return absl::NotFoundError(absl::StrCat(unit_name, " does not exist"));
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows,
      db->Exec(
          absl::StrCat(
              "SELECT role, part_serial, ", Micros("installed_time"), ", installed_hours, ",
              Micros("removed_time"),
              ", coalesce(removed_hours, 0), coalesce(removal_reason, ''), removed_time IS NULL "
              "FROM modules WHERE unit_id = $1 ORDER BY role, installed_hours, module_id"),
          {Param::Text(unit.String(0, 0))}));
  std::vector<Module> out;
  for (int r = 0; r < rows.rows(); ++r) {
    Module& m = out.emplace_back();
    m.name = api::ModuleName(*serial, rows.String(r, 0));
    m.role = rows.String(r, 0);
    m.part_serial = rows.String(r, 1);
    m.installed_time = absl::FromUnixMicros(internal::IntOr0(rows, r, 2));
    m.installed_hours = internal::DoubleOr0(rows, r, 3);
    if (!rows.IsNull(r, 4)) m.removed_time = absl::FromUnixMicros(internal::IntOr0(rows, r, 4));
    m.removed_hours = internal::DoubleOr0(rows, r, 5);
    m.removal_reason = rows.String(r, 6);
    m.current = rows.Bool(r, 7);
  }
  return out;
}

absl::StatusOr<FailureMode> CatalogueStore::GetFailureMode(const std::string& name) {
  INSDIAG_ASSIGN_OR_RETURN(auto id, api::ResourceId(name, api::kFailureModes, "name"));
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  INSDIAG_ASSIGN_OR_RETURN(auto modes, LoadModes(*db, "", "", id));
  if (modes.empty()) return absl::NotFoundError(absl::StrCat(name, " does not exist"));
  return modes.front();
}

absl::StatusOr<std::vector<FailureMode>> CatalogueStore::ListFailureModes(const std::string& unit_type,
                                                                              const std::string& module_role) {
  INSDIAG_ASSIGN_OR_RETURN(auto db, list_pool_.Acquire());
  return LoadModes(*db, unit_type.empty() ? "" : UnitTypeId(unit_type), module_role, "");
}

}  // namespace insdiag::kb
