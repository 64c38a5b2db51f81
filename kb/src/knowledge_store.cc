#include "insdiag/kb/knowledge_store.h"

#include <absl/strings/match.h>
#include <absl/strings/str_cat.h>
#include <absl/strings/str_join.h>

#include <map>
#include <set>

#include "report_rows.h"
#include "store_util.h"

namespace insdiag::kb {
namespace {

using internal::Micros;

constexpr char kUnitTypePrefix[] = "unitTypes";
constexpr char kModePrefix[] = "failureModes";

const char* DirectionName(v1::Signature::Direction d) {
  return d == v1::Signature::UP ? "UP" : d == v1::Signature::DOWN ? "DOWN" : "EITHER";
}

std::string Bool(bool b) { return b ? "true" : "false"; }

// unitTypes/{t} or a bare display name → {t}.
std::string UnitTypeId(const std::string& name) {
  return absl::StartsWith(name, "unitTypes/") ? name.substr(10) : name;
}

absl::StatusOr<v1::UnitType> LoadUnitType(Connection& db, const std::string& id) {
  auto rows = db.Exec("SELECT display_name, description FROM unit_types WHERE unit_type = $1", {Param::Text(id)});
  if (!rows.ok()) return rows.status();
  if (rows->rows() == 0) return absl::NotFoundError(absl::StrCat("unitTypes/", id, " does not exist"));
  v1::UnitType t;
  t.set_name(absl::StrCat("unitTypes/", id));
  t.set_display_name(rows->String(0, 0));
  t.set_description(rows->String(0, 1));
  auto nominal = db.Exec(
      "SELECT parameter, value, tolerance, unit FROM nominal_parameters WHERE unit_type = $1 ORDER BY position",
      {Param::Text(id)});
  if (!nominal.ok()) return nominal.status();
  for (int r = 0; r < nominal->rows(); ++r) {
    auto* p = t.add_nominal();
    p->set_name(nominal->String(r, 0));
    p->set_value(internal::DoubleOr0(*nominal, r, 1));
    p->set_tolerance(internal::DoubleOr0(*nominal, r, 2));
    p->set_unit(nominal->String(r, 3));
  }
  return t;
}

// The fleet's operating hours of a unit type.
absl::StatusOr<double> FleetExposure(Connection& db, const std::string& unit_type_id) {
  auto rows = db.Exec("SELECT coalesce(sum(operating_hours), 0) FROM units WHERE unit_type = $1",
                      {Param::Text(unit_type_id)});
  if (!rows.ok()) return rows.status();
  return internal::DoubleOr0(*rows, 0, 0);
}

v1::DiagnosisSettings SettingsFor(const std::string& unit_type_id) {
  auto catalogue = BuiltinFailureModeCatalogue(unit_type_id);
  if (catalogue.ok()) return catalogue->settings();
  // A unit type without a catalogue has no modes; these settings only rank
  // healthy against unknown. Take the first catalogue's constants.
  auto all = BuiltinFailureModeCatalogues();
  return all.empty() ? v1::DiagnosisSettings() : all.front().settings();
}

absl::StatusOr<std::vector<v1::FailureMode>> LoadModes(Connection& db, const std::string& unit_type_id,
                                                       const std::string& role, const std::string& only_mode) {
  auto rows = db.Exec(
      "SELECT f.failure_mode, f.unit_type, f.module_role, f.display_name, f.description, f.expert_rate_per_hour, "
      "f.weibull_shape, f.weibull_scale_hours, "
      "(SELECT count(*) FROM failure_records r WHERE r.failure_mode = f.failure_mode AND r.confirmed) "
      "FROM failure_modes f WHERE ($1::text IS NULL OR f.unit_type = $1) AND ($2::text IS NULL OR f.module_role = $2) "
      "AND ($3::text IS NULL OR f.failure_mode = $3) ORDER BY f.unit_type, f.module_role, f.failure_mode",
      {Param::TextOrNull(unit_type_id), Param::TextOrNull(role), Param::TextOrNull(only_mode)});
  if (!rows.ok()) return rows.status();
  std::vector<v1::FailureMode> modes;
  std::map<std::string, std::size_t> index;
  std::map<std::string, double> exposure;
  std::map<std::string, v1::DiagnosisSettings> settings;
  for (int r = 0; r < rows->rows(); ++r) {
    v1::FailureMode m;
    m.set_name(absl::StrCat(kModePrefix, "/", rows->String(r, 0)));
    const std::string type = rows->String(r, 1);
    m.set_unit_type(absl::StrCat(kUnitTypePrefix, "/", type));
    m.set_module_role(rows->String(r, 2));
    m.set_display_name(rows->String(r, 3));
    m.set_description(rows->String(r, 4));
    m.set_expert_rate_per_million_hours(internal::DoubleOr0(*rows, r, 5) * 1e6);
    m.set_weibull_shape(internal::DoubleOr0(*rows, r, 6));
    m.set_weibull_scale_hours(internal::DoubleOr0(*rows, r, 7));
    m.set_confirmed_failures(internal::IntOr0(*rows, r, 8));
    if (!exposure.contains(type)) {
      // Once per unit type: the fleet's hours, and its catalogue's settings (parsed from JSON).
      auto hours = FleetExposure(db, type);
      if (!hours.ok()) return hours.status();
      exposure[type] = *hours;
      settings[type] = SettingsFor(type);
    }
    m.set_rate_per_million_hours(
        1e6 * ModeRatePerHour(m, m.confirmed_failures(), exposure[type], settings[type]));
    index[rows->String(r, 0)] = modes.size();
    modes.push_back(std::move(m));
  }
  if (modes.empty()) return modes;
  std::vector<std::string> ids;
  for (const auto& [id, i] : index) ids.push_back(id);
  auto terms = db.Exec(
      "SELECT failure_mode, parameter, direction, scale, common, fraction, expert_change, expert_spread, change, "
      "spread, confirmed_cases FROM signature_terms WHERE failure_mode = ANY($1::text[]) "
      "ORDER BY failure_mode, position",
      {Param::TextArray(ids)});
  if (!terms.ok()) return terms.status();
  for (int r = 0; r < terms->rows(); ++r) {
    auto* s = modes[index[terms->String(r, 0)]].add_signature();
    s->set_parameter(terms->String(r, 1));
    v1::Signature::Direction d = v1::Signature::EITHER;
    v1::Signature::Direction_Parse(terms->String(r, 2), &d);
    s->set_direction(d);
    s->set_scale(terms->String(r, 3));
    s->set_common(terms->Bool(r, 4));
    s->set_fraction(internal::DoubleOr0(*terms, r, 5));
    s->set_expert_change(internal::DoubleOr0(*terms, r, 6));
    s->set_expert_spread(internal::DoubleOr0(*terms, r, 7));
    s->set_change(internal::DoubleOr0(*terms, r, 8));
    s->set_spread(internal::DoubleOr0(*terms, r, 9));
    s->set_confirmed_cases(static_cast<int>(internal::IntOr0(*terms, r, 10)));
  }
  return modes;
}

using internal::LoadReport;

constexpr char kRecordColumns[] =
    "SELECT r.record_id::text, u.serial, m.role, coalesce(r.failure_mode, ''), coalesce(r.analysis_id::text, ''), "
    "r.operating_hours, r.confirmed, r.repaired, r.censored, (extract(epoch FROM r.record_time) * 1000000)::bigint, "
    "r.no_fault_found, r.repair_action, (extract(epoch FROM r.detected_time) * 1000000)::bigint, "
    "coalesce(r.diagnosis_id::text, ''), r.notes, r.record_time::text, r.revision "
    "FROM failure_records r JOIN modules m USING (module_id) JOIN units u ON u.unit_id = r.unit_id ";

v1::FailureRecord RecordFromRow(const Result& rows, int r) {
  v1::FailureRecord f;
  f.set_name(absl::StrCat("failureRecords/", rows.String(r, 0)));
  f.set_module(absl::StrCat("units/", rows.String(r, 1), "/modules/", rows.String(r, 2)));
  if (!rows.String(r, 3).empty()) f.set_failure_mode(absl::StrCat(kModePrefix, "/", rows.String(r, 3)));
  if (!rows.String(r, 4).empty()) f.set_analysis(absl::StrCat("analyses/", rows.String(r, 4)));
  f.set_operating_hours(internal::DoubleOr0(rows, r, 5));
  f.set_confirmed(rows.Bool(r, 6));
  f.set_repaired(rows.Bool(r, 7));
  f.set_censored(rows.Bool(r, 8));
  *f.mutable_record_time() = internal::TimestampOfMicros(internal::IntOr0(rows, r, 9));
  f.set_no_fault_found(rows.Bool(r, 10));
  f.set_repair_action(rows.String(r, 11));
  *f.mutable_detected_time() = internal::TimestampOfMicros(internal::IntOr0(rows, r, 12));
  if (!rows.String(r, 13).empty()) f.set_diagnosis(absl::StrCat("diagnoses/", rows.String(r, 13)));
  f.set_notes(rows.String(r, 14));
  f.set_revision(static_cast<int>(internal::IntOr0(rows, r, 16)));
  return f;
}

// The failure mode `mode_id` (named `mode_name` by the caller, in `field`)
// exists and is a failure of module role `role`; "" passes. NOT_FOUND or
// INVALID_ARGUMENT naming the field otherwise.
absl::Status CheckModeOfRole(Connection& db, const std::string& mode_id, const std::string& mode_name,
                             const std::string& role, const std::string& field) {
  if (mode_id.empty()) return absl::OkStatus();
  auto mode = db.Exec("SELECT module_role FROM failure_modes WHERE failure_mode = $1", {Param::Text(mode_id)});
  if (!mode.ok()) return mode.status();
  if (mode->rows() == 0) return absl::NotFoundError(absl::StrCat(field, ": ", mode_name, " does not exist"));
  if (mode->String(0, 0) != role) {
    return absl::InvalidArgumentError(
        absl::StrCat(field, ": ", mode_name, " is a failure of ", mode->String(0, 0), ", not of ", role));
  }
  return absl::OkStatus();
}

// A record's facts, checked before any database work: its failure mode's id
// ("" for none), or INVALID_ARGUMENT naming the field.
absl::StatusOr<std::string> CheckedFacts(const v1::FailureRecord& facts) {
  std::string mode_id;
  if (!facts.failure_mode().empty()) {
    auto id = internal::IdOf(facts.failure_mode(), kModePrefix, "failure_record.failure_mode");
    if (!id.ok()) return id.status();
    mode_id = *id;
  }
  if (facts.confirmed() && mode_id.empty()) {
    return absl::InvalidArgumentError("failure_record.failure_mode: a confirmed failure names its failure mode");
  }
  if (facts.confirmed() && facts.no_fault_found()) {
    return absl::InvalidArgumentError("failure_record.no_fault_found: a confirmed failure cannot be no-fault-found");
  }
  if (!(facts.operating_hours() >= 0)) {
    return absl::InvalidArgumentError("failure_record.operating_hours: must be 0 or more");
  }
  return mode_id;
}

absl::StatusOr<v1::FailureRecord> GetRecord(Connection& db, const std::string& id) {
  auto rows = db.Exec(absl::StrCat(kRecordColumns, "WHERE r.record_id = $1::uuid"), {Param::Text(id)});
  if (!rows.ok()) return rows.status();
  if (rows->rows() == 0) return absl::NotFoundError(absl::StrCat("failureRecords/", id, " does not exist"));
  return RecordFromRow(*rows, 0);
}

struct Written {
  std::string record_id;
};

// Inserts a validated record; module_id resolved by the caller.
absl::StatusOr<std::string> InsertRecord(Connection& db, std::int64_t module_id, std::int64_t unit_id,
                                         const v1::FailureRecord& f, const std::string& mode_id,
                                         const std::string& analysis_id, const std::string& diagnosis_id) {
  auto rows = db.Exec(
      "INSERT INTO failure_records (module_id, unit_id, failure_mode, analysis_id, diagnosis_id, detected_time, "
      "operating_hours, confirmed, no_fault_found, censored, repaired, repair_action, notes) "
      "VALUES ($1, $2, $3, $4::uuid, $5::uuid, coalesce($6::timestamptz, now()), $7, $8, $9, $10, $11, $12, $13) "
      "RETURNING record_id::text",
      {Param::Int(module_id), Param::Int(unit_id), Param::TextOrNull(mode_id), Param::TextOrNull(analysis_id),
       Param::TextOrNull(diagnosis_id),
       f.has_detected_time() ? Param::Text(internal::TimestampText(f.detected_time())) : Param::Null(),
       Param::Double(f.operating_hours()), Param::Text(Bool(f.confirmed())), Param::Text(Bool(f.no_fault_found())),
       Param::Text(Bool(f.censored())), Param::Text(Bool(f.repaired())), Param::Text(f.repair_action()),
       Param::Text(f.notes())});
  if (!rows.ok()) return rows.status();
  return rows->String(0, 0);
}

// The current module of `role` in unit `unit_id` (registering the unit's
// modules when it has none yet).
absl::StatusOr<std::int64_t> CurrentModule(Connection& db, std::int64_t unit_id, const std::string& role) {
  auto ensured = db.Exec(
      "INSERT INTO modules (unit_id, role, installed_time) "
      "SELECT u.unit_id, r.role, u.create_time FROM units u CROSS JOIN module_roles r "
      "WHERE u.unit_id = $1 AND NOT EXISTS (SELECT 1 FROM modules m WHERE m.unit_id = u.unit_id "
      "AND m.role = r.role AND m.removed_time IS NULL)",
      {Param::Int(unit_id)});
  if (!ensured.ok()) return ensured.status();
  auto rows = db.Exec("SELECT module_id FROM modules WHERE unit_id = $1 AND role = $2 AND removed_time IS NULL",
                      {Param::Int(unit_id), Param::Text(role)});
  if (!rows.ok()) return rows.status();
  if (rows->rows() == 0) return absl::InvalidArgumentError(absl::StrCat("module: '", role, "' is not a module role"));
  return rows->Int(0, 0);
}

// Re-derives the signature of `mode_id` from the expert values and every
// confirmed case with an analysis (kb/diagnosis.h, RefineSignature).
absl::Status RefineMode(Connection& db, const std::string& mode_id) {
  auto modes = LoadModes(db, "", "", mode_id);
  if (!modes.ok()) return modes.status();
  if (modes->empty()) return absl::OkStatus();
  const v1::FailureMode& mode = modes->front();
  const std::string type_id = UnitTypeId(mode.unit_type());
  auto unit_type = LoadUnitType(db, type_id);
  if (!unit_type.ok()) return unit_type.status();
  const v1::DiagnosisSettings settings = SettingsFor(type_id);
  auto cases = db.Exec(
      "SELECT DISTINCT analysis_id::text FROM failure_records WHERE failure_mode = $1 AND confirmed "
      "AND analysis_id IS NOT NULL",
      {Param::Text(mode_id)});
  if (!cases.ok()) return cases.status();
  std::vector<Evidence> evidence;
  for (int r = 0; r < cases->rows(); ++r) {
    auto report = LoadReport(db, cases->String(r, 0));
    if (!report.ok()) continue;  // a case whose analysis is gone no longer refines
    evidence.push_back(EvidenceFromReport(*report, *unit_type, settings));
  }
  for (int position = 0; position < mode.signature_size(); ++position) {
    std::vector<double> values;
    for (const auto& e : evidence) {
      if (auto v = CaseValue(mode.signature(position), e)) values.push_back(*v);
    }
    const v1::Signature refined = RefineSignature(mode.signature(position), values, settings);
    auto updated = db.Exec(
        "UPDATE signature_terms SET change = $3, spread = $4, confirmed_cases = $5 WHERE failure_mode = $1 AND "
        "position = $2",
        {Param::Text(mode_id), Param::Int(position), Param::Double(refined.change()), Param::Double(refined.spread()),
         Param::Int(refined.confirmed_cases())});
    if (!updated.ok()) return updated.status();
  }
  return db.Exec("UPDATE failure_modes SET update_time = now() WHERE failure_mode = $1", {Param::Text(mode_id)})
      .status();
}

absl::StatusOr<v1::Diagnosis> LoadDiagnosis(Connection& db, const std::string& id) {
  auto rows = db.Exec(
      "SELECT d.body, coalesce(d.record_id::text, ''), coalesce(r.confirmed, false), coalesce(m.role, '') "
      "FROM diagnoses d LEFT JOIN failure_records r ON r.record_id = d.record_id "
      "LEFT JOIN modules m ON m.module_id = r.module_id WHERE d.diagnosis_id = $1::uuid",
      {Param::Text(id)}, ResultFormat::kBinary);
  if (!rows.ok()) return rows.status();
  if (rows->rows() == 0) return absl::NotFoundError(absl::StrCat("diagnoses/", id, " does not exist"));
  v1::Diagnosis d;
  d.ParseFromString(std::string(rows->Get(0, 0)));
  if (!rows->Get(0, 1).empty()) {
    d.set_failure_record(absl::StrCat("failureRecords/", rows->String(0, 1)));
    d.set_confirmed(rows->Get(0, 2) == std::string_view("\x01", 1));
    d.set_resolved_module(rows->String(0, 3));
  }
  return d;
}

}  // namespace

absl::Status KnowledgeStore::Seed(std::span<const v1::UnitType> unit_types,
                                  std::span<const v1::FailureModeCatalogue> catalogues) {
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  return (*db)->InTransaction([&]() -> absl::Status {
    auto locked = (*db)->Exec("SELECT pg_advisory_xact_lock($1)", {Param::Int(AdvisoryLockKey("insdiag.seed"))});
    if (!locked.ok()) return locked.status();
    for (const auto& t : unit_types) {
      const std::string id = UnitTypeId(t.name());
      auto upserted = (*db)->Exec(
          "INSERT INTO unit_types (unit_type, display_name, description) VALUES ($1, $2, $3) "
          "ON CONFLICT (unit_type) DO UPDATE SET display_name = EXCLUDED.display_name, "
          "description = EXCLUDED.description, update_time = now()",
          {Param::Text(id), Param::Text(t.display_name()), Param::Text(t.description())});
      if (!upserted.ok()) return upserted.status();
      auto cleared = (*db)->Exec("DELETE FROM nominal_parameters WHERE unit_type = $1", {Param::Text(id)});
      if (!cleared.ok()) return cleared.status();
      int position = 0;
      for (const auto& p : t.nominal()) {
        auto inserted = (*db)->Exec(
            "INSERT INTO nominal_parameters (unit_type, parameter, value, tolerance, unit, position) "
            "VALUES ($1, $2, $3, $4, $5, $6)",
            {Param::Text(id), Param::Text(p.name()), Param::Double(p.value()), Param::Double(p.tolerance()),
             Param::Text(p.unit()), Param::Int(position++)});
        if (!inserted.ok()) return inserted.status();
      }
    }
    for (const auto& catalogue : catalogues) {
      auto modes = ExpandCatalogue(catalogue);
      if (!modes.ok()) return modes.status();
      for (const auto& mode : *modes) {
        const std::string id = mode.name().substr(sizeof kModePrefix);
        auto upserted = (*db)->Exec(
            "INSERT INTO failure_modes (failure_mode, unit_type, module_role, display_name, description, "
            "expert_rate_per_hour, weibull_shape, weibull_scale_hours) VALUES ($1, $2, $3, $4, $5, $6, $7, $8) "
            "ON CONFLICT (failure_mode) DO UPDATE SET unit_type = EXCLUDED.unit_type, module_role = "
            "EXCLUDED.module_role, display_name = EXCLUDED.display_name, description = EXCLUDED.description, "
            "expert_rate_per_hour = EXCLUDED.expert_rate_per_hour, weibull_shape = EXCLUDED.weibull_shape, "
            "weibull_scale_hours = EXCLUDED.weibull_scale_hours",
            {Param::Text(id), Param::Text(UnitTypeId(mode.unit_type())), Param::Text(mode.module_role()),
             Param::Text(mode.display_name()), Param::Text(mode.description()),
             Param::Double(mode.expert_rate_per_million_hours() * 1e-6), Param::Double(mode.weibull_shape()),
             Param::Double(mode.weibull_scale_hours())});
        if (!upserted.ok()) return upserted.status();
        // Keep refined terms while the expert's signature is unchanged.
        std::vector<std::string> wanted;
        for (const auto& s : mode.signature()) {
          wanted.push_back(absl::StrCat(s.parameter(), "|", DirectionName(s.direction()), "|", s.scale(), "|",
                                        Bool(s.common()), "|", s.fraction(), "|", s.expert_change(), "|",
                                        s.expert_spread()));
        }
        auto existing = (*db)->Exec(
            "SELECT parameter || '|' || direction || '|' || scale || '|' || common::text || '|' || fraction::text "
            "|| '|' || expert_change::text || '|' || expert_spread::text FROM signature_terms WHERE failure_mode = $1 "
            "ORDER BY position",
            {Param::Text(id)});
        if (!existing.ok()) return existing.status();
        std::vector<std::string> have;
        for (int r = 0; r < existing->rows(); ++r) have.push_back(existing->String(r, 0));
        if (have == wanted) continue;
        auto cleared = (*db)->Exec("DELETE FROM signature_terms WHERE failure_mode = $1", {Param::Text(id)});
        if (!cleared.ok()) return cleared.status();
        int position = 0;
        for (const auto& s : mode.signature()) {
          auto inserted = (*db)->Exec(
              "INSERT INTO signature_terms (failure_mode, position, parameter, direction, scale, common, fraction, "
              "expert_change, expert_spread, change, spread) VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $8, $9)",
              {Param::Text(id), Param::Int(position++), Param::Text(s.parameter()),
               Param::Text(DirectionName(s.direction())), Param::Text(s.scale()), Param::Text(Bool(s.common())),
               Param::Double(s.fraction()), Param::Double(s.expert_change()), Param::Double(s.expert_spread())});
          if (!inserted.ok()) return inserted.status();
        }
      }
    }
    return absl::OkStatus();
  });
}

absl::StatusOr<v1::UnitType> KnowledgeStore::GetUnitType(const std::string& name) {
  auto id = internal::IdOf(name, kUnitTypePrefix, "name");
  if (!id.ok()) return id.status();
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  return LoadUnitType(**db, *id);
}

absl::StatusOr<std::vector<v1::UnitType>> KnowledgeStore::ListUnitTypes() {
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  auto rows = (*db)->Exec("SELECT unit_type FROM unit_types ORDER BY unit_type");
  if (!rows.ok()) return rows.status();
  std::vector<v1::UnitType> out;
  for (int r = 0; r < rows->rows(); ++r) {
    auto t = LoadUnitType(**db, rows->String(r, 0));
    if (!t.ok()) return t.status();
    out.push_back(std::move(*t));
  }
  return out;
}

namespace {
constexpr char kUnitColumns[] =
    "SELECT serial, coalesce(unit_type, ''), operating_hours, (extract(epoch FROM create_time) * 1000000)::bigint, "
    "coalesce(batch, ''), (extract(epoch FROM commission_time) * 1000000)::bigint, retired_time IS NOT NULL FROM units ";

v1::Unit UnitFromRow(const Result& rows, int r) {
  v1::Unit u;
  u.set_name(absl::StrCat("units/", rows.String(r, 0)));
  if (!rows.String(r, 1).empty()) u.set_unit_type(absl::StrCat("unitTypes/", rows.String(r, 1)));
  u.set_operating_hours(internal::DoubleOr0(rows, r, 2));
  *u.mutable_create_time() = internal::TimestampOfMicros(internal::IntOr0(rows, r, 3));
  u.set_batch(rows.String(r, 4));
  if (!rows.IsNull(r, 5)) *u.mutable_commission_time() = internal::TimestampOfMicros(internal::IntOr0(rows, r, 5));
  u.set_retired(rows.Bool(r, 6));
  return u;
}
}  // namespace

absl::StatusOr<v1::Unit> KnowledgeStore::GetUnit(const std::string& name) {
  auto serial = internal::IdOf(name, "units", "name");
  if (!serial.ok()) return serial.status();
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  auto rows = (*db)->Exec(absl::StrCat(kUnitColumns, "WHERE serial = $1"), {Param::Text(*serial)});
  if (!rows.ok()) return rows.status();
  if (rows->rows() == 0) return absl::NotFoundError(absl::StrCat(name, " does not exist"));
  return UnitFromRow(*rows, 0);
}

absl::StatusOr<std::pair<std::vector<v1::Unit>, std::string>> KnowledgeStore::ListUnits(const PageQuery& page,
                                                                                         const std::string& unit_type,
                                                                                         const std::string& batch) {
  const int size = internal::ClampPageSize(page.page_size);
  std::string after_serial;
  if (!page.page_token.empty()) {
    auto key = internal::DecodeToken(page.page_token);
    if (!key.ok()) return key.status();
    after_serial = key->second;
  }
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  auto rows = (*db)->Exec(
      absl::StrCat(kUnitColumns,
                   "WHERE ($2::text IS NULL OR unit_type = $2) AND ($3::text IS NULL OR batch = $3) "
                   "AND ($4::text IS NULL OR serial > $4) ORDER BY serial LIMIT $1"),
      {Param::Int(size + 1), Param::TextOrNull(unit_type.empty() ? "" : UnitTypeId(unit_type)),
       Param::TextOrNull(batch), Param::TextOrNull(after_serial)});
  if (!rows.ok()) return rows.status();
  std::vector<v1::Unit> units;
  const int shown = std::min(rows->rows(), size);
  for (int r = 0; r < shown; ++r) units.push_back(UnitFromRow(*rows, r));
  std::string next;
  if (rows->rows() > size) next = internal::EncodeToken("", rows->String(shown - 1, 0));
  return std::make_pair(std::move(units), next);
}

absl::StatusOr<std::vector<v1::Module>> KnowledgeStore::ListModules(const std::string& unit_name) {
  auto serial = internal::IdOf(unit_name, "units", "parent");
  if (!serial.ok()) return serial.status();
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  auto unit = (*db)->Exec("SELECT unit_id FROM units WHERE serial = $1", {Param::Text(*serial)});
  if (!unit.ok()) return unit.status();
  if (unit->rows() == 0) return absl::NotFoundError(absl::StrCat(unit_name, " does not exist"));
  auto rows = (*db)->Exec(
      absl::StrCat("SELECT role, part_serial, ", Micros("installed_time"), ", installed_hours, ", Micros("removed_time"),
                   ", coalesce(removed_hours, 0), coalesce(removal_reason, ''), removed_time IS NULL "
                   "FROM modules WHERE unit_id = $1 ORDER BY role, installed_hours, module_id"),
      {Param::Text(unit->String(0, 0))});
  if (!rows.ok()) return rows.status();
  std::vector<v1::Module> out;
  for (int r = 0; r < rows->rows(); ++r) {
    v1::Module m;
    m.set_name(absl::StrCat(unit_name, "/modules/", rows->String(r, 0)));
    m.set_role(rows->String(r, 0));
    m.set_part_serial(rows->String(r, 1));
    *m.mutable_installed_time() = internal::TimestampOfMicros(internal::IntOr0(*rows, r, 2));
    m.set_installed_hours(internal::DoubleOr0(*rows, r, 3));
    if (!rows->IsNull(r, 4)) *m.mutable_removed_time() = internal::TimestampOfMicros(internal::IntOr0(*rows, r, 4));
    m.set_removed_hours(internal::DoubleOr0(*rows, r, 5));
    m.set_removal_reason(rows->String(r, 6));
    m.set_current(rows->Bool(r, 7));
    out.push_back(std::move(m));
  }
  return out;
}

absl::StatusOr<v1::FailureMode> KnowledgeStore::GetFailureMode(const std::string& name) {
  auto id = internal::IdOf(name, kModePrefix, "name");
  if (!id.ok()) return id.status();
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  auto modes = LoadModes(**db, "", "", *id);
  if (!modes.ok()) return modes.status();
  if (modes->empty()) return absl::NotFoundError(absl::StrCat(name, " does not exist"));
  return modes->front();
}

absl::StatusOr<std::vector<v1::FailureMode>> KnowledgeStore::ListFailureModes(const std::string& unit_type,
                                                                              const std::string& module_role) {
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  return LoadModes(**db, unit_type.empty() ? "" : UnitTypeId(unit_type), module_role, "");
}

absl::StatusOr<v1::FailureRecord> KnowledgeStore::CreateFailureRecord(const v1::FailureRecord& record) {
  // failure_record.module: units/{serial}/modules/{role}
  const std::string& module = record.module();
  const auto slash = module.find("/modules/");
  if (!absl::StartsWith(module, "units/") || slash == std::string::npos || slash <= 6 ||
      slash + 9 >= module.size()) {
    return absl::InvalidArgumentError(
        absl::StrCat("failure_record.module: '", module, "' is not units/{unit}/modules/{module}"));
  }
  const std::string serial = module.substr(6, slash - 6);
  const std::string role = module.substr(slash + 9);
  auto checked_mode = CheckedFacts(record);
  if (!checked_mode.ok()) return checked_mode.status();
  const std::string mode_id = *checked_mode;
  std::string analysis_id;
  if (!record.analysis().empty()) {
    auto id = internal::UuidOf(record.analysis(), "analyses", "failure_record.analysis");
    if (!id.ok()) return id.status();
    analysis_id = *id;
  }
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  std::string id;
  const absl::Status status = (*db)->InTransaction([&]() -> absl::Status {
    auto unit = (*db)->Exec("SELECT unit_id FROM units WHERE serial = $1", {Param::Text(serial)});
    if (!unit.ok()) return unit.status();
    if (unit->rows() == 0) return absl::NotFoundError(absl::StrCat("failure_record.module: units/", serial, " does not exist"));
    auto roles = (*db)->Exec("SELECT 1 FROM module_roles WHERE role = $1", {Param::Text(role)});
    if (!roles.ok()) return roles.status();
    if (roles->rows() == 0) {
      return absl::InvalidArgumentError(absl::StrCat("failure_record.module: '", role, "' is not a module role"));
    }
    if (auto fits = CheckModeOfRole(**db, mode_id, record.failure_mode(), role, "failure_record.failure_mode");
        !fits.ok()) {
      return fits;
    }
    auto unit_id = unit->Int(0, 0);
    if (!unit_id.ok()) return unit_id.status();
    auto module_id = CurrentModule(**db, *unit_id, role);
    if (!module_id.ok()) return module_id.status();
    auto written = InsertRecord(**db, *module_id, *unit_id, record, mode_id, analysis_id, "");
    if (!written.ok()) {
      if (written.status().code() == absl::StatusCode::kFailedPrecondition && !analysis_id.empty()) {
        return absl::NotFoundError(absl::StrCat("failure_record.analysis: ", record.analysis(), " does not exist"));
      }
      return written.status();
    }
    id = *written;
    if (record.confirmed()) return RefineMode(**db, mode_id);
    return absl::OkStatus();
  });
  if (!status.ok()) return status;
  return GetRecord(**db, id);
}

absl::StatusOr<v1::FailureRecord> KnowledgeStore::CorrectFailureRecord(const std::string& name,
                                                                       const v1::FailureRecord& facts,
                                                                       const std::string& reason) {
  auto id = internal::UuidOf(name, "failureRecords", "name");
  if (!id.ok()) return id.status();
  if (reason.empty()) return absl::InvalidArgumentError("reason: required (why the record was wrong)");
  auto checked_mode = CheckedFacts(facts);
  if (!checked_mode.ok()) return checked_mode.status();
  const std::string mode_id = *checked_mode;
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  const absl::Status status = (*db)->InTransaction([&]() -> absl::Status {
    auto current = (*db)->Exec(
        "SELECT coalesce(r.failure_mode, ''), m.role, r.confirmed FROM failure_records r JOIN modules m "
        "USING (module_id) WHERE r.record_id = $1::uuid FOR UPDATE OF r",
        {Param::Text(*id)});
    if (!current.ok()) return current.status();
    if (current->rows() == 0) return absl::NotFoundError(absl::StrCat(name, " does not exist"));
    const std::string old_mode = current->String(0, 0), role = current->String(0, 1);
    const bool was_confirmed = current->Bool(0, 2);
    if (auto fits = CheckModeOfRole(**db, mode_id, facts.failure_mode(), role, "failure_record.failure_mode");
        !fits.ok()) {
      return fits;
    }
    auto kept = (*db)->Exec(
        "INSERT INTO failure_record_revisions (record_id, revision, failure_mode, detected_time, operating_hours, "
        "confirmed, no_fault_found, censored, repaired, repair_action, notes, record_time, reason) "
        "SELECT record_id, revision, failure_mode, detected_time, operating_hours, confirmed, no_fault_found, "
        "censored, repaired, repair_action, notes, record_time, $2 FROM failure_records WHERE record_id = $1::uuid",
        {Param::Text(*id), Param::Text(reason)});
    if (!kept.ok()) return kept.status();
    auto updated = (*db)->Exec(
        "UPDATE failure_records SET failure_mode = $2, operating_hours = $3, confirmed = $4, no_fault_found = $5, "
        "censored = $6, repaired = $7, repair_action = $8, notes = $9, "
        "detected_time = coalesce($10::timestamptz, detected_time), record_time = now(), revision = revision + 1 "
        "WHERE record_id = $1::uuid",
        {Param::Text(*id), Param::TextOrNull(mode_id), Param::Double(facts.operating_hours()),
         Param::Text(facts.confirmed() ? "true" : "false"), Param::Text(facts.no_fault_found() ? "true" : "false"),
         Param::Text(facts.censored() ? "true" : "false"), Param::Text(facts.repaired() ? "true" : "false"),
         Param::Text(facts.repair_action()), Param::Text(facts.notes()),
         facts.has_detected_time() ? Param::Text(internal::TimestampText(facts.detected_time())) : Param::Null()});
    if (!updated.ok()) return updated.status();
    // The signatures learn from confirmed cases: a mode the record leaves or joins is refined again.
    if (was_confirmed && !old_mode.empty()) {
      if (auto refined = RefineMode(**db, old_mode); !refined.ok()) return refined;
    }
    if (facts.confirmed() && mode_id != old_mode) return RefineMode(**db, mode_id);
    return absl::OkStatus();
  });
  if (!status.ok()) return status;
  return GetRecord(**db, *id);
}

absl::StatusOr<std::vector<v1::FailureRecordRevision>> KnowledgeStore::ListFailureRecordRevisions(
    const std::string& name) {
  auto id = internal::UuidOf(name, "failureRecords", "name");
  if (!id.ok()) return id.status();
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  auto current = GetRecord(**db, *id);
  if (!current.ok()) return current.status();
  auto rows = (*db)->Exec(
      absl::StrCat("SELECT revision, coalesce(failure_mode, ''), operating_hours, confirmed, no_fault_found, censored, "
                   "repaired, repair_action, notes, ", Micros("detected_time"), ", ", Micros("record_time"), ", ",
                   Micros("superseded_time"), ", reason FROM failure_record_revisions WHERE record_id = $1::uuid "
                   "ORDER BY revision"),
      {Param::Text(*id)});
  if (!rows.ok()) return rows.status();
  std::vector<v1::FailureRecordRevision> revisions;
  for (int r = 0; r < rows->rows(); ++r) {
    v1::FailureRecordRevision& v = revisions.emplace_back();
    v1::FailureRecord& f = *v.mutable_failure_record();
    f = *current;  // name, module, analysis and diagnosis do not change
    f.set_revision(static_cast<int>(internal::IntOr0(*rows, r, 0)));
    f.clear_failure_mode();
    if (!rows->String(r, 1).empty()) f.set_failure_mode(absl::StrCat(kModePrefix, "/", rows->String(r, 1)));
    f.set_operating_hours(internal::DoubleOr0(*rows, r, 2));
    f.set_confirmed(rows->Bool(r, 3));
    f.set_no_fault_found(rows->Bool(r, 4));
    f.set_censored(rows->Bool(r, 5));
    f.set_repaired(rows->Bool(r, 6));
    f.set_repair_action(rows->String(r, 7));
    f.set_notes(rows->String(r, 8));
    *f.mutable_detected_time() = internal::TimestampOfMicros(internal::IntOr0(*rows, r, 9));
    *f.mutable_record_time() = internal::TimestampOfMicros(internal::IntOr0(*rows, r, 10));
    *v.mutable_superseded_time() = internal::TimestampOfMicros(internal::IntOr0(*rows, r, 11));
    v.set_reason(rows->String(r, 12));
  }
  return revisions;
}

absl::StatusOr<std::pair<std::vector<v1::FailureRecord>, std::string>> KnowledgeStore::ListFailureRecords(
    const RecordQuery& query) {
  const int size = internal::ClampPageSize(query.page.page_size);
  std::string serial, role, mode_id;
  if (!query.module.empty()) {
    const auto slash = query.module.find("/modules/");
    if (!absl::StartsWith(query.module, "units/") || slash == std::string::npos) {
      return absl::InvalidArgumentError(absl::StrCat("module: '", query.module, "' is not units/{unit}/modules/{module}"));
    }
    serial = query.module.substr(6, slash - 6);
    role = query.module.substr(slash + 9);
  }
  if (!query.unit.empty()) {
    auto s = internal::IdOf(query.unit, "units", "unit");
    if (!s.ok()) return s.status();
    serial = *s;
  }
  if (!query.failure_mode.empty()) {
    auto m = internal::IdOf(query.failure_mode, kModePrefix, "failure_mode");
    if (!m.ok()) return m.status();
    mode_id = *m;
  }
  std::vector<Param> params = {Param::Int(size + 1), Param::TextOrNull(serial), Param::TextOrNull(role),
                               Param::TextOrNull(mode_id)};
  std::string after = "true";
  if (!query.page.page_token.empty()) {
    auto key = internal::DecodeToken(query.page.page_token);
    if (!key.ok()) return key.status();
    if (!internal::IsUuid(key->second)) return absl::InvalidArgumentError("page_token is not one this server issued");
    params.push_back(Param::Text(key->first));
    params.push_back(Param::Text(key->second));
    after = "(r.record_time, r.record_id) < ($5::timestamptz, $6::uuid)";
  }
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  auto rows = (*db)->Exec(absl::StrCat(kRecordColumns,
                                       "WHERE ($2::text IS NULL OR u.serial = $2) AND ($3::text IS NULL OR m.role = $3) "
                                       "AND ($4::text IS NULL OR r.failure_mode = $4) AND ",
                                       after, " ORDER BY r.record_time DESC, r.record_id DESC LIMIT $1"),
                          params);
  if (!rows.ok()) return rows.status();
  std::vector<v1::FailureRecord> out;
  const int shown = std::min(rows->rows(), size);
  for (int r = 0; r < shown; ++r) out.push_back(RecordFromRow(*rows, r));
  std::string next;
  if (rows->rows() > size) next = internal::EncodeToken(rows->String(shown - 1, 15), rows->String(shown - 1, 0));
  return std::make_pair(std::move(out), next);
}

absl::StatusOr<v1::Diagnosis> KnowledgeStore::CreateDiagnosis(const std::string& analysis_name) {
  auto analysis_id = internal::UuidOf(analysis_name, "analyses", "analysis");
  if (!analysis_id.ok()) return analysis_id.status();
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  auto unit = (*db)->Exec(
      "SELECT a.unit_id, u.serial, coalesce(u.unit_type, ''), coalesce(a.unit_hours, u.operating_hours), "
      "coalesce((SELECT max(p.unit_hours) FROM analyses p WHERE p.unit_id = a.unit_id AND p.state = 'SUCCEEDED' "
      "AND p.create_time < a.create_time), 0) "
      "FROM analyses a JOIN units u ON u.unit_id = a.unit_id WHERE a.analysis_id = $1::uuid",
      {Param::Text(*analysis_id)});
  if (!unit.ok()) return unit.status();
  if (unit->rows() == 0) return absl::NotFoundError(absl::StrCat(analysis_name, " does not exist"));
  const std::string unit_id = unit->String(0, 0);
  const std::string serial = unit->String(0, 1);
  const std::string type_id = unit->String(0, 2);
  if (type_id.empty()) {
    return absl::FailedPreconditionError(absl::StrCat("units/", serial, " has no unit type (its runs name none): ",
                                                      "there is no nominal model to diagnose against"));
  }
  auto report = LoadReport(**db, *analysis_id);
  if (!report.ok()) return report.status();
  auto unit_type = LoadUnitType(**db, type_id);
  if (!unit_type.ok()) {
    if (unit_type.status().code() == absl::StatusCode::kNotFound) {
      return absl::FailedPreconditionError(absl::StrCat("units/", serial, " is of unit type '", type_id,
                                                        "', which the knowledge base does not know"));
    }
    return unit_type.status();
  }
  auto modes = LoadModes(**db, type_id, "", "");
  if (!modes.ok()) return modes.status();
  auto fleet = FleetExposure(**db, type_id);
  if (!fleet.ok()) return fleet.status();
  const v1::DiagnosisSettings settings = SettingsFor(type_id);
  PriorInputs prior;
  const double hours = internal::DoubleOr0(*unit, 0, 3);
  const double previous = internal::DoubleOr0(*unit, 0, 4);
  prior.exposure_hours = std::max(hours - previous, 0.0);
  prior.fleet_exposure_hours = *fleet;
  for (const auto& m : *modes) prior.confirmed_failures[m.name()] = m.confirmed_failures();

  v1::Diagnosis diagnosis = Diagnose(EvidenceFromReport(*report, *unit_type, settings), *modes, settings, prior);
  diagnosis.set_analysis(analysis_name);
  diagnosis.set_unit(absl::StrCat("units/", serial));
  std::string id;
  const absl::Status status = (*db)->InTransaction([&]() -> absl::Status {
    auto made = (*db)->Exec("SELECT gen_random_uuid()::text, " + Micros("now()"));
    if (!made.ok()) return made.status();
    id = made->String(0, 0);
    diagnosis.set_name(absl::StrCat("diagnoses/", id));
    *diagnosis.mutable_create_time() = internal::TimestampOfMicros(internal::IntOr0(*made, 0, 1));
    const DiagnosisHeadline headline = HeadlineOf(diagnosis);
    const v1::Candidate* top = headline.top;
    std::string body;
    diagnosis.SerializeToString(&body);
    std::vector<std::string> notes(diagnosis.notes().begin(), diagnosis.notes().end());
    auto inserted = (*db)->Exec(
        "INSERT INTO diagnoses (diagnosis_id, analysis_id, unit_id, fault_probability, top_module, top_failure_mode, "
        "top_probability, body, notes, create_time) VALUES ($1::uuid, $2::uuid, $3, $4, $5, $6, $7, $8, $9::text[], "
        "to_timestamp($10::double precision / 1000000))",
        {Param::Text(id), Param::Text(*analysis_id), Param::Text(unit_id), Param::Double(headline.fault_probability),
         Param::Text(top ? top->module() : ""), Param::Text(top ? top->failure_mode() : ""),
         Param::Double(top ? top->probability() : 0.0), Param::Bytes(body),
         Param::TextArray(notes),
         Param::Int(internal::MicrosOf(diagnosis.create_time()))});
    if (!inserted.ok()) return inserted.status();
    int rank = 0;
    for (const auto& c : diagnosis.candidates()) {
      std::vector<std::string> evidence(c.evidence().begin(), c.evidence().end());
      auto row = (*db)->Exec(
          "INSERT INTO diagnosis_candidates (diagnosis_id, rank, module, failure_mode, probability, evidence) "
          "VALUES ($1::uuid, $2, $3, $4, $5, $6::text[])",
          {Param::Text(id), Param::Int(rank++), Param::Text(c.module()), Param::Text(c.failure_mode()),
           Param::Double(c.probability()), Param::TextArray(evidence)});
      if (!row.ok()) return row.status();
    }
    return absl::OkStatus();
  });
  if (!status.ok()) return status;
  return diagnosis;
}

absl::StatusOr<v1::Diagnosis> KnowledgeStore::GetDiagnosis(const std::string& name) {
  auto id = internal::UuidOf(name, "diagnoses", "name");
  if (!id.ok()) return id.status();
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  return LoadDiagnosis(**db, *id);
}

absl::StatusOr<std::pair<std::vector<v1::Diagnosis>, std::string>> KnowledgeStore::ListDiagnoses(
    const DiagnosisQuery& query) {
  const int size = internal::ClampPageSize(query.page.page_size);
  std::string analysis_id, serial;
  if (!query.analysis.empty()) {
    auto id = internal::UuidOf(query.analysis, "analyses", "analysis");
    if (!id.ok()) return id.status();
    analysis_id = *id;
  }
  if (!query.unit.empty()) {
    auto s = internal::IdOf(query.unit, "units", "unit");
    if (!s.ok()) return s.status();
    serial = *s;
  }
  std::vector<Param> params = {Param::Int(size + 1), Param::TextOrNull(analysis_id), Param::TextOrNull(serial)};
  std::string after = "true";
  if (!query.page.page_token.empty()) {
    auto key = internal::DecodeToken(query.page.page_token);
    if (!key.ok()) return key.status();
    if (!internal::IsUuid(key->second)) return absl::InvalidArgumentError("page_token is not one this server issued");
    params.push_back(Param::Text(key->first));
    params.push_back(Param::Text(key->second));
    after = "(d.create_time, d.diagnosis_id) < ($4::timestamptz, $5::uuid)";
  }
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  auto rows = (*db)->Exec(
      absl::StrCat("SELECT d.diagnosis_id::text, d.create_time::text FROM diagnoses d JOIN units u USING (unit_id) "
                   "WHERE ($2::uuid IS NULL OR d.analysis_id = $2::uuid) AND ($3::text IS NULL OR u.serial = $3) AND ",
                   after, " ORDER BY d.create_time DESC, d.diagnosis_id DESC LIMIT $1"),
      params);
  if (!rows.ok()) return rows.status();
  std::vector<v1::Diagnosis> out;
  const int shown = std::min(rows->rows(), size);
  for (int r = 0; r < shown; ++r) {
    auto d = LoadDiagnosis(**db, rows->String(r, 0));
    if (!d.ok()) return d.status();
    out.push_back(std::move(*d));
  }
  std::string next;
  if (rows->rows() > size) next = internal::EncodeToken(rows->String(shown - 1, 1), rows->String(shown - 1, 0));
  return std::make_pair(std::move(out), next);
}

absl::StatusOr<v1::Diagnosis> KnowledgeStore::ResolveDiagnosis(const v1::ResolveDiagnosisRequest& request) {
  auto id = internal::UuidOf(request.name(), "diagnoses", "name");
  if (!id.ok()) return id.status();
  if (request.module().empty()) return absl::InvalidArgumentError("module: the module found faulty (or suspected) is required");
  std::string mode_id;
  if (!request.failure_mode().empty()) {
    auto m = internal::IdOf(request.failure_mode(), kModePrefix, "failure_mode");
    if (!m.ok()) return m.status();
    mode_id = *m;
  }
  if (request.confirmed() && mode_id.empty()) {
    return absl::InvalidArgumentError("failure_mode: a confirmed diagnosis names the failure mode found");
  }
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  const absl::Status status = (*db)->InTransaction([&]() -> absl::Status {
    auto row = (*db)->Exec(
        "SELECT d.analysis_id::text, d.unit_id, d.record_id IS NOT NULL, coalesce(a.unit_hours, u.operating_hours) "
        "FROM diagnoses d JOIN analyses a USING (analysis_id) JOIN units u ON u.unit_id = d.unit_id "
        "WHERE d.diagnosis_id = $1::uuid FOR UPDATE OF d",
        {Param::Text(*id)});
    if (!row.ok()) return row.status();
    if (row->rows() == 0) return absl::NotFoundError(absl::StrCat(request.name(), " does not exist"));
    if (row->Bool(0, 2)) return absl::FailedPreconditionError(absl::StrCat(request.name(), " is already resolved"));
    auto unit_id = row->Int(0, 1);
    if (!unit_id.ok()) return unit_id.status();
    auto roles = (*db)->Exec("SELECT 1 FROM module_roles WHERE role = $1", {Param::Text(request.module())});
    if (!roles.ok()) return roles.status();
    if (roles->rows() == 0) {
      return absl::InvalidArgumentError(absl::StrCat("module: '", request.module(), "' is not a module role"));
    }
    if (auto fits = CheckModeOfRole(**db, mode_id, request.failure_mode(), request.module(), "failure_mode");
        !fits.ok()) {
      return fits;
    }
    auto module_id = CurrentModule(**db, *unit_id, request.module());
    if (!module_id.ok()) return module_id.status();
    v1::FailureRecord record;
    record.set_operating_hours(internal::DoubleOr0(*row, 0, 3));
    record.set_confirmed(request.confirmed());
    record.set_no_fault_found(!request.confirmed());
    record.set_repaired(request.confirmed() && !request.repair_action().empty());
    record.set_repair_action(request.repair_action());
    record.set_notes(request.notes());
    auto written = InsertRecord(**db, *module_id, *unit_id, record, mode_id, row->String(0, 0), *id);
    if (!written.ok()) return written.status();
    auto linked = (*db)->Exec("UPDATE diagnoses SET record_id = $2::uuid WHERE diagnosis_id = $1::uuid",
                              {Param::Text(*id), Param::Text(*written)});
    if (!linked.ok()) return linked.status();
    if (request.confirmed()) return RefineMode(**db, mode_id);
    return absl::OkStatus();
  });
  if (!status.ok()) return status;
  return LoadDiagnosis(**db, *id);
}

absl::Status KnowledgeStore::RefineSignatures(const std::string& unit_type) {
  auto db = pool_.Acquire();
  if (!db.ok()) return db.status();
  auto modes = (*db)->Exec(
      "SELECT DISTINCT r.failure_mode FROM failure_records r JOIN failure_modes f USING (failure_mode) "
      "WHERE r.confirmed AND r.analysis_id IS NOT NULL AND ($1::text IS NULL OR f.unit_type = $1) ORDER BY 1",
      {Param::TextOrNull(unit_type.empty() ? "" : UnitTypeId(unit_type))});
  if (!modes.ok()) return modes.status();
  for (int r = 0; r < modes->rows(); ++r) {
    const std::string mode_id = modes->String(r, 0);
    if (auto s = (*db)->InTransaction([&] { return RefineMode(**db, mode_id); }); !s.ok()) return s;
  }
  return absl::OkStatus();
}

}  // namespace insdiag::kb
