// The planned fleet written into the knowledge base with COPY, in one
// transaction: units, modules, runs (metadata only), analyses with their
// identified parameters and effect candidates, diagnoses with their
// candidates, and failure records.
#include <absl/strings/escaping.h>
#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>

#include <chrono>
#include <map>

#include "generator.h"
#include "insdiag/api/sha256.h"
#include "insdiag/engine/candidate_source.h"
#include "insdiag/engine/status_macros.h"
#include "insdiag/kb/copy_text.h"
#include "insdiag/kb/diagnosis.h"
#include "insdiag/kb/knowledge_messages.h"

namespace insdiag::kb::generator {
namespace {

// The generated candidates are score-test candidates, as the engine names them.
const std::string kScoreSource(engine::CandidateSourceName(engine::CandidateSource::kScore));

constexpr std::size_t kCopyChunkBytes = 1 << 20;

// Ids: {salt:8}-{kind:4}-8{index}-a{index}-{index}: one generation's ids share
// a prefix and increase with the index (ids of one kind append to their index).
Uuid MakeId(std::uint32_t salt, std::uint16_t kind, std::uint64_t index) {
  Uuid id;
  id.hi = (static_cast<std::uint64_t>(salt) << 32) | (static_cast<std::uint64_t>(kind) << 16) | 0x8000U |
          ((index >> 60) & 0xfffU);
  id.lo = 0xa000000000000000ULL | (index & 0x0fffffffffffffffULL);
  return id;
}

enum IdKind : std::uint16_t { kRunIds = 1, kAnalysisIds, kRecordIds, kDiagnosisIds };

absl::StatusOr<std::int64_t> CopyItems(Connection& db, std::string_view sql, std::size_t count,
                                       absl::FunctionRef<void(std::size_t, std::string&)> emit) {
  std::size_t next = 0;
  return db.CopyIn(sql, [&](std::string& buffer) {
    while (next < count && buffer.size() < kCopyChunkBytes) emit(next++, buffer);
    return next < count;
  });
}

absl::StatusOr<std::vector<std::int64_t>> ReserveIds(Connection& db, const char* table, const char* column,
                                                     std::int64_t count) {
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows,
      db.Exec("SELECT nextval(pg_get_serial_sequence($1, $2)) FROM generate_series(1, $3)",
              {Param::Text(table), Param::Text(column), Param::Int(count)}));
  std::vector<std::int64_t> ids;
  ids.reserve(static_cast<std::size_t>(count));
  for (int r = 0; r < rows.rows(); ++r) ids.push_back(rows.Int(r, 0).value_or(0));
  return ids;
}

// The foreign keys of the tables the generator fills are dropped for the
// load and added back (validated in one join per key) before commit: per-row
// checks would cost minutes for millions of rows. The tables are locked
// meanwhile (ACCESS EXCLUSIVE, until the transaction ends).
constexpr char kLoadedTables[] =
    "{modules,runs,analyses,identified_parameters,effect_candidates,diagnoses,diagnosis_candidates,failure_records}";

absl::StatusOr<std::vector<std::string>> DropForeignKeys(Connection& db) {
  INSDIAG_ASSIGN_OR_RETURN(
      auto keys,
      db.Exec("SELECT format('ALTER TABLE %s DROP CONSTRAINT %I', conrelid::regclass, conname), "
              "format('ALTER TABLE %s ADD CONSTRAINT %I %s', conrelid::regclass, conname, "
              "pg_get_constraintdef(oid)) "
              "FROM pg_constraint WHERE contype = 'f' AND conrelid = ANY($1::regclass[]) ORDER BY "
              "conrelid, conname",
              {Param::Text(kLoadedTables)}));
  std::vector<std::string> restore;
  for (int r = 0; r < keys.rows(); ++r) {
    INSDIAG_RETURN_IF_ERROR(db.ExecScript(keys.String(r, 0)));
    restore.push_back(keys.String(r, 1));
  }
  return restore;
}

// The runs carry no samples: the digest of none.
std::string EmptyDigest() { return absl::BytesToHexString(api::Sha256("")); }

const char* KindName(TestKind kind) {
  switch (kind) {
    case TestKind::kPeriodic: return "periodic";
    case TestKind::kFailure: return "failure";
    case TestKind::kNoFaultFound: return "no fault found";
    case TestKind::kRetest: return "retest after repair";
  }
  return "";
}

class Writer {
 public:
  Writer(Connection& db, const Model& m, Plan& plan, GeneratedFleet& out,
         absl::FunctionRef<void(const std::string&)> progress)
      : db_(db), m_(m), plan_(plan), out_(out), progress_(progress) {}

  absl::Status WriteAll();

 private:
  // Runs one COPY, reporting its rows and time; `count`, when given, receives the rows.
  absl::Status Copy(const std::string& what, std::string_view sql, std::size_t items,
                    absl::FunctionRef<void(std::size_t, std::string&)> emit, std::int64_t* count);
  absl::Status Prepare();
  absl::Status CopyUnits();
  absl::Status CopyTests();
  absl::Status CopyDiagnoses();
  absl::Status CopyRecords();
  absl::Status LinkDiagnosesToRecords();
  absl::Status RestoreForeignKeys(const std::vector<std::string>& restore);
  void CountOutcomes();
  void EmitUnit(std::size_t i, std::string& buffer) const;
  void EmitModules(std::size_t i, std::string& buffer) const;
  void EmitRun(std::size_t g, std::string& buffer) const;
  void EmitAnalysis(std::size_t g, std::string& buffer) const;
  void EmitIdentified(std::size_t g, std::string& buffer) const;
  void EmitCandidates(std::size_t g, std::string& buffer) const;
  void EmitDiagnosis(std::size_t d, std::string& buffer, std::string& candidates) const;
  void EmitRecords(std::size_t i, std::string& buffer) const;

  const Test& TestAt(std::size_t g) const {
    const auto [unit, test] = plan_.order[g];
    return plan_.units[static_cast<std::size_t>(unit)].tests[static_cast<std::size_t>(test)];
  }
  Uuid RunId(const Test& t) const { return MakeId(m_.salt, kRunIds, static_cast<std::uint64_t>(t.global)); }
  Uuid AnalysisId(const Test& t) const { return MakeId(m_.salt, kAnalysisIds, static_cast<std::uint64_t>(t.global)); }
  Uuid DiagnosisId(std::int64_t d) const { return MakeId(m_.salt, kDiagnosisIds, static_cast<std::uint64_t>(d)); }
  Diagnosis DiagnosisOf(std::size_t d) const;

  Connection& db_;
  const Model& m_;
  Plan& plan_;
  GeneratedFleet& out_;
  absl::FunctionRef<void(const std::string&)> progress_;
  std::vector<int> parameter_ids_;
  std::vector<std::pair<int, int>> diagnosed_;  // (unit, test) of each diagnosis, in diagnosis order
  std::vector<std::uint64_t> first_record_;     // per unit: index of its first failure record
  PriorInputs prior_;
  std::string digest_;
  std::string generated_note_;
};

absl::Status Writer::Copy(const std::string& what, std::string_view sql, std::size_t items,
                          absl::FunctionRef<void(std::size_t, std::string&)> emit, std::int64_t* count) {
  const auto start = std::chrono::steady_clock::now();
  INSDIAG_ASSIGN_OR_RETURN(auto rows, CopyItems(db_, sql, items, emit));
  if (count != nullptr) *count = rows;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  progress_(absl::StrCat(what, ": ", rows, " rows in ", absl::StrFormat("%.1f", seconds), " s"));
  return absl::OkStatus();
}

absl::Status Writer::Prepare() {
  std::vector<std::string> names;
  for (const auto& t : m_.identified) names.push_back(t.name);
  const Param literal = Param::TextArray(names);
  INSDIAG_ASSIGN_OR_RETURN(
      auto inserted,
      db_.Exec(
          "INSERT INTO parameter_names (name) SELECT unnest($1::text[]) ON CONFLICT DO NOTHING",
          {literal}));
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows,
      db_.Exec("SELECT name, parameter_id FROM parameter_names WHERE name = ANY($1::text[])",
               {literal}));
  std::map<std::string, int> ids;
  for (int r = 0; r < rows.rows(); ++r)
    ids[rows.String(r, 0)] = static_cast<int>(rows.Int(r, 1).value_or(0));
  for (const auto& t : m_.identified) parameter_ids_.push_back(ids[t.name]);

  INSDIAG_ASSIGN_OR_RETURN(
      auto unit_ids,
      ReserveIds(db_, "units", "unit_id", static_cast<std::int64_t>(plan_.units.size())));
  INSDIAG_ASSIGN_OR_RETURN(auto module_ids, ReserveIds(db_, "modules", "module_id", plan_.parts));
  std::size_t next_module = 0;
  std::uint64_t next_record = 0;
  for (std::size_t i = 0; i < plan_.units.size(); ++i) {
    UnitPlan& u = plan_.units[i];
    u.unit_id = (unit_ids)[i];
    for (auto& part : u.parts) part.module_id = (module_ids)[next_module++];
    first_record_.push_back(next_record);
    for (const auto& f : u.failures) next_record += f.realised ? 1 : 0;
    next_record += u.no_fault_found.size();
    if (u.retired) {
      for (const auto& part : u.parts) next_record += part.withdrawn ? 1 : 0;
    }
  }
  // Diagnoses: every unit's latest test and every unscheduled one, their
  // priors from the generated fleet's exposure and confirmed failures.
  for (std::size_t i = 0; i < plan_.units.size(); ++i) {
    UnitPlan& u = plan_.units[i];
    prior_.fleet_exposure_hours += u.end_hours;
    for (const auto& f : u.failures) {
      if (f.realised) ++prior_.confirmed_failures[m_.modes[static_cast<std::size_t>(f.mode)].name];
    }
    for (std::size_t t = 0; t < u.tests.size(); ++t) {
      if (!Diagnosed(u, t)) continue;
      u.tests[t].diagnosis = static_cast<std::int64_t>(diagnosed_.size());
      diagnosed_.emplace_back(static_cast<int>(i), static_cast<int>(t));
    }
  }
  digest_ = EmptyDigest();
  generated_note_ = absl::StrCat("insdiag-fleet seed ", m_.seed, ": metadata only, no samples");
  return absl::OkStatus();
}

void Writer::EmitUnit(std::size_t i, std::string& buffer) const {
  const UnitPlan& u = plan_.units[i];
  CopyRow row(buffer);
  row.Int(u.unit_id).Text(u.serial).Text(m_.unit_type_id).Time(u.commission_us);
  row.Text(plan_.batches[static_cast<std::size_t>(u.batch)].name).Time(u.commission_us).Double(u.end_hours);
  if (u.retired) {
    row.Time(u.end_us);
  } else {
    row.Null();
  }
  row.End();
}

void Writer::EmitModules(std::size_t i, std::string& buffer) const {
  const UnitPlan& u = plan_.units[i];
  for (const Part& part : u.parts) {
    CopyRow row(buffer);
    row.Int(part.module_id).Int(u.unit_id).Text(m_.roles[static_cast<std::size_t>(part.role)]);
    row.Text(absl::StrCat("P", absl::Hex(m_.salt, absl::kZeroPad8), "-", part.module_id));
    row.Time(part.installed_us).Double(part.installed_hours);
    if (part.removed_us == kNever) {
      row.Null().Null().Null();
    } else if (part.withdrawn) {
      row.Time(part.removed_us).Double(part.removed_hours).Text("unit retired");
    } else {
      const Failure& f = u.failures[static_cast<std::size_t>(part.failure)];
      row.Time(part.removed_us).Double(part.removed_hours);
      row.Text(absl::StrCat("failed: ", m_.mode_models[static_cast<std::size_t>(f.mode)].id));
    }
    row.End();
  }
}

void Writer::EmitRun(std::size_t g, std::string& buffer) const {
  const UnitPlan& u = plan_.units[static_cast<std::size_t>(plan_.order[g].first)];
  const Test& t = TestAt(g);
  const v1::FleetProfile& p = m_.profile;
  CopyRow row(buffer);
  row.Id(RunId(t)).Int(u.unit_id).Text(m_.run_format).Text(u.serial).Text(m_.unit_type_id);
  row.Double(p.site_latitude_deg()).Double(p.site_longitude_deg()).Double(p.site_height_m());
  row.Text(absl::StrCat(R"([["generated",")", generated_note_, R"("],["test",")", KindName(t.kind),
                        R"("],["test_duration_s",")", p.test_duration_s(), R"("]])"));
  row.Bool(false).Int(0).Double(1.0 / p.sample_rate_hz()).Double(0).Double(0).Text(digest_);
  row.Time(t.time_us).Time(t.time_us);
  row.End();
}

void Writer::EmitAnalysis(std::size_t g, std::string& buffer) const {
  const auto [unit, test] = plan_.order[g];
  const UnitPlan& u = plan_.units[static_cast<std::size_t>(unit)];
  const Test& t = TestAt(g);
  const TestValues v = Measure(m_, plan_, static_cast<std::size_t>(unit), static_cast<std::size_t>(test));
  CopyRow row(buffer);
  row.Id(AnalysisId(t)).Id(RunId(t)).Int(u.unit_id).Text("SUCCEEDED").Int(1).Double(1).Text("done");
  row.Text(v1::AnalysisReport::Verdict_Name(v.verdict)).Double(v.nis_mean).Double(t.hours);
  row.Time(t.time_us).Time(t.time_us).Time(t.time_us).Time(t.time_us);
  row.End();
}

void Writer::EmitIdentified(std::size_t g, std::string& buffer) const {
  const auto [unit, test] = plan_.order[g];
  const Test& t = TestAt(g);
  const TestValues v = Measure(m_, plan_, static_cast<std::size_t>(unit), static_cast<std::size_t>(test));
  const Uuid id = AnalysisId(t);
  for (std::size_t i = 0; i < m_.identified.size(); ++i) {
    const IdentifiedTerm& term = m_.identified[i];
    const double value = IdentifiedValue(term, v.log_ratio[i]);
    CopyRow row(buffer);
    row.Id(id).Int(parameter_ids_[i]).Double(value).Double(IdentifiedStdError(m_, term, value)).Text(term.method);
    row.Double(term.nominal);
    row.End();
  }
}

void Writer::EmitCandidates(std::size_t g, std::string& buffer) const {
  const auto [unit, test] = plan_.order[g];
  const UnitPlan& u = plan_.units[static_cast<std::size_t>(unit)];
  const Test& t = TestAt(g);
  const TestValues v = Measure(m_, plan_, static_cast<std::size_t>(unit), static_cast<std::size_t>(test));
  const Uuid id = AnalysisId(t);
  for (const auto& r : Candidates(m_, v, Diagnosed(u, static_cast<std::size_t>(test)))) {
    const EffectTerm& e = m_.effects[static_cast<std::size_t>(r.effect)];
    CopyRow row(buffer);
    row.Id(id)
        .Text(e.name)
        .Text(e.family)
        .Bool(false)
        .Text(kScoreSource)
        .Double(r.statistic)
        .Int(1)
        .Double(r.p_value);
    row.Double(r.p_holm).Double(r.estimate).Double(r.std_error).Text(e.unit).Bool(true);
    row.End();
  }
}

Diagnosis Writer::DiagnosisOf(std::size_t d) const {
  const auto [unit, test] = diagnosed_[d];
  const UnitPlan& u = plan_.units[static_cast<std::size_t>(unit)];
  const Test& t = u.tests[static_cast<std::size_t>(test)];
  const v1::AnalysisReport report =
      ReportOf(m_, Measure(m_, plan_, static_cast<std::size_t>(unit), static_cast<std::size_t>(test)));
  PriorInputs prior = prior_;
  prior.exposure_hours = t.hours - (test > 0 ? u.tests[static_cast<std::size_t>(test) - 1].hours : 0.0);
  Diagnosis diagnosis =
      Diagnose(EvidenceFromReport(FindingsOf(report), m_.unit_type, m_.settings), m_.modes, m_.settings, prior);
  diagnosis.analysis = absl::StrCat("analyses/", UuidText(AnalysisId(t)));
  diagnosis.unit = absl::StrCat("units/", u.serial);
  return diagnosis;
}

// A diagnosis row, and its candidates' rows into `candidates` (a diagnosis
// costs ~1 ms to compute: once is enough).
void Writer::EmitDiagnosis(std::size_t d, std::string& buffer, std::string& candidates) const {
  const auto [unit, test] = diagnosed_[d];
  const UnitPlan& u = plan_.units[static_cast<std::size_t>(unit)];
  const Test& t = u.tests[static_cast<std::size_t>(test)];
  const Diagnosis diagnosis = DiagnosisOf(d);
  int rank = 0;
  for (const Candidate& c : diagnosis.candidates) {
    CopyRow row(candidates);
    row.Id(DiagnosisId(t.diagnosis)).Int(rank++).Text(c.module).Text(c.failure_mode).Double(c.probability);
    row.TextArray(c.evidence);
    row.End();
  }
  const DiagnosisHeadline headline = HeadlineOf(diagnosis);
  // Kept as the diagnosis store keeps it.
  const std::string body = EncodeDiagnosis(diagnosis, absl::StrCat("diagnoses/", UuidText(DiagnosisId(t.diagnosis))),
                                           absl::FromUnixMicros(t.time_us));
  CopyRow row(buffer);
  row.Id(DiagnosisId(t.diagnosis)).Id(AnalysisId(t)).Int(u.unit_id).Double(headline.fault_probability);
  row.Text(headline.top ? headline.top->module : "").Text(headline.top ? headline.top->failure_mode : "");
  row.Double(headline.top ? headline.top->probability : 0.0).Bytes(body);
  row.TextArray(diagnosis.notes).Time(t.time_us);
  row.End();
}

// Failure records of one unit: confirmed failures, removals without fault
// found, and a censored record per part withdrawn with a retired unit.
void Writer::EmitRecords(std::size_t i, std::string& buffer) const {
  const UnitPlan& u = plan_.units[i];
  const std::int64_t delay = RecordDelay(m_);
  std::uint64_t next = first_record_[i];
  const auto start = [&](std::int64_t module_id, const std::string& mode) -> CopyRow {
    CopyRow row(buffer);
    row.Id(MakeId(m_.salt, kRecordIds, next++)).Int(module_id).Int(u.unit_id);
    if (mode.empty()) {
      row.Null();
    } else {
      row.Text(mode);
    }
    return row;
  };
  for (const auto& f : u.failures) {
    if (!f.realised) continue;
    const Test& t = u.tests[static_cast<std::size_t>(f.test)];
    CopyRow row = start(u.parts[static_cast<std::size_t>(f.part)].module_id, m_.mode_models[static_cast<std::size_t>(f.mode)].id);
    row.Id(AnalysisId(t)).Id(DiagnosisId(t.diagnosis)).Time(f.time_us).Double(f.hours);
    row.Bool(true).Bool(false).Bool(false).Bool(true).Text("module replaced").Text("").Time(f.time_us + delay);
    row.End();
  }
  for (const auto& n : u.no_fault_found) {
    const Test& t = u.tests[static_cast<std::size_t>(n.test)];
    std::int64_t module_id = 0;
    for (const auto& part : u.parts) {
      if (part.role == n.role && part.installed_us <= n.time_us && n.time_us < part.removed_us) module_id = part.module_id;
    }
    CopyRow row = start(module_id, "");
    row.Id(AnalysisId(t)).Id(DiagnosisId(t.diagnosis)).Time(n.time_us).Double(n.hours);
    row.Bool(false).Bool(true).Bool(false).Bool(false).Text("none: no fault found, returned to service").Text("");
    row.Time(n.time_us + delay);
    row.End();
  }
  if (u.retired) {
    for (const auto& part : u.parts) {
      if (!part.withdrawn) continue;
      CopyRow row = start(part.module_id, "");
      row.Null().Null().Time(u.end_us).Double(u.end_hours);
      row.Bool(false).Bool(false).Bool(true).Bool(false).Text("").Text("unit retired").Time(u.end_us);
      row.End();
    }
  }
}

// Units first: a taken serial is the one conflict a caller can fix.
absl::Status Writer::CopyUnits() {
  const std::size_t units = plan_.units.size();
  if (auto s = Copy("units",
                    "COPY units (unit_id, serial, unit_type, create_time, batch, commission_time, operating_hours, "
                    "retired_time) FROM STDIN",
                    units, [&](std::size_t i, std::string& b) { EmitUnit(i, b); }, &out_.units);
      !s.ok()) {
    return s.code() == absl::StatusCode::kAlreadyExists
               ? absl::AlreadyExistsError(absl::StrCat("serials ", m_.serial_prefix,
                                                       "-… are taken: choose another serial prefix (", s.message(),
                                                       ")"))
               : s;
  }
  return Copy("modules",
              "COPY modules (module_id, unit_id, role, part_serial, installed_time, installed_hours, "
              "removed_time, removed_hours, removal_reason) FROM STDIN",
              units, [&](std::size_t i, std::string& b) { EmitModules(i, b); }, &out_.modules);
}

// Every test's run and analysis, with the analysis's identified parameters
// and effect candidates.
absl::Status Writer::CopyTests() {
  const std::size_t tests = plan_.order.size();
  if (auto s = Copy("runs",
                    "COPY runs (run_id, unit_id, format, unit_serial, unit_type, site_latitude_deg, "
                    "site_longitude_deg, site_height_m, extra_metadata, has_temperature, sample_count, "
                    "nominal_interval_s, duration_s, first_t, sha256, create_time, test_time) FROM STDIN",
                    tests, [&](std::size_t g, std::string& b) { EmitRun(g, b); }, &out_.runs);
      !s.ok()) {
    return s;
  }
  if (auto s = Copy("analyses",
                    "COPY analyses (analysis_id, run_id, unit_id, state, attempts, progress_fraction, progress_stage, "
                    "verdict, nis_mean, unit_hours, create_time, update_time, start_time, end_time) FROM STDIN",
                    tests, [&](std::size_t g, std::string& b) { EmitAnalysis(g, b); }, &out_.analyses);
      !s.ok()) {
    return s;
  }
  if (auto s = Copy("identified parameters",
                    "COPY identified_parameters (analysis_id, parameter_id, value, std_error, method, a_priori) "
                    "FROM STDIN",
                    tests, [&](std::size_t g, std::string& b) { EmitIdentified(g, b); }, &out_.identified_parameters);
      !s.ok()) {
    return s;
  }
  return Copy("effect candidates",
              "COPY effect_candidates (analysis_id, name, family, per_family, source, statistic, "
              "degrees_of_freedom, p_value, p_value_holm, estimate, std_error, unit, identifiable) FROM STDIN",
              tests, [&](std::size_t g, std::string& b) { EmitCandidates(g, b); }, &out_.effect_candidates);
}

// The diagnoses, then their candidates (gathered while the diagnoses were
// written) in one more COPY.
absl::Status Writer::CopyDiagnoses() {
  std::string candidates;
  if (auto s = Copy("diagnoses",
                    "COPY diagnoses (diagnosis_id, analysis_id, unit_id, fault_probability, top_module, "
                    "top_failure_mode, top_probability, body, notes, create_time) FROM STDIN",
                    diagnosed_.size(), [&](std::size_t d, std::string& b) { EmitDiagnosis(d, b, candidates); },
                    &out_.diagnoses);
      !s.ok()) {
    return s;
  }
  return Copy("diagnosis candidates",
              "COPY diagnosis_candidates (diagnosis_id, rank, module, failure_mode, probability, evidence) "
              "FROM STDIN",
              1, [&](std::size_t, std::string& b) { b.swap(candidates); }, nullptr);
}

absl::Status Writer::CopyRecords() {
  return Copy("failure records",
              "COPY failure_records (record_id, module_id, unit_id, failure_mode, analysis_id, diagnosis_id, "
              "detected_time, operating_hours, confirmed, no_fault_found, censored, repaired, repair_action, "
              "notes, record_time) FROM STDIN",
              plan_.units.size(), [&](std::size_t i, std::string& b) { EmitRecords(i, b); }, nullptr);
}

// The diagnoses of failures and removals are resolved by their records.
absl::Status Writer::LinkDiagnosesToRecords() {
  auto linked = db_.Exec(
      "UPDATE diagnoses d SET record_id = r.record_id FROM failure_records r "
      "WHERE r.diagnosis_id = d.diagnosis_id AND d.record_id IS NULL AND r.record_id >= $1::uuid AND r.record_id <= $2::uuid",
      {Param::Text(UuidText(MakeId(m_.salt, kRecordIds, 0))),
       Param::Text(UuidText(MakeId(m_.salt, kRecordIds, 0x0fffffffffffffffULL)))});
  return linked.status();
}

absl::Status Writer::RestoreForeignKeys(const std::vector<std::string>& restore) {
  const auto start = std::chrono::steady_clock::now();
  for (const auto& statement : restore) {
    INSDIAG_RETURN_IF_ERROR(db_.ExecScript(statement));
  }
  progress_(absl::StrCat("validated ", restore.size(), " foreign keys in ",
                         absl::StrFormat("%.1f", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()),
                         " s"));
  return absl::OkStatus();
}

void Writer::CountOutcomes() {
  for (const auto& u : plan_.units) {
    out_.retired_units += u.retired ? 1 : 0;
    for (const auto& f : u.failures) out_.confirmed_failures += f.realised ? 1 : 0;
    out_.no_fault_found += static_cast<std::int64_t>(u.no_fault_found.size());
    for (const auto& part : u.parts) out_.censored_records += part.withdrawn ? 1 : 0;
  }
}

absl::Status Writer::WriteAll() {
  INSDIAG_RETURN_IF_ERROR(Prepare());
  // Validating the keys joins millions of rows: give the joins memory.
  INSDIAG_RETURN_IF_ERROR(db_.ExecScript("SET LOCAL work_mem = '256MB'"));
  INSDIAG_ASSIGN_OR_RETURN(auto restore, DropForeignKeys(db_));
  INSDIAG_RETURN_IF_ERROR(CopyUnits());
  INSDIAG_RETURN_IF_ERROR(CopyTests());
  INSDIAG_RETURN_IF_ERROR(CopyDiagnoses());
  INSDIAG_RETURN_IF_ERROR(CopyRecords());
  INSDIAG_RETURN_IF_ERROR(LinkDiagnosesToRecords());
  INSDIAG_RETURN_IF_ERROR(RestoreForeignKeys(restore));
  CountOutcomes();
  return absl::OkStatus();
}

}  // namespace

absl::Status WriteFleet(Connection& db, const Model& m, Plan& plan, GeneratedFleet& out,
                        absl::FunctionRef<void(const std::string&)> progress) {
  return Writer(db, m, plan, out, progress).WriteAll();
}

}  // namespace insdiag::kb::generator
