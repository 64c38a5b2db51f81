#include "insdiag/kb/diagnosis_store.h"

#include <absl/strings/str_cat.h>
#include <absl/strings/str_join.h>

#include <algorithm>

#include "catalogue_rows.h"
#include "failure_record_writes.h"
#include "history_rows.h"
#include "insdiag/api/resource_names.h"
#include "insdiag/engine/status_macros.h"
#include "insdiag/kb/diagnosis.h"
#include "insdiag/kb/failure_record.h"
#include "insdiag/kb/unit_history.h"
#include "report_rows.h"
#include "signature_refinement.h"
#include "store_util.h"

namespace insdiag::kb {
namespace {

using internal::CheckModeOfRole;
using internal::CheckModuleRole;
using internal::CurrentModule;
using internal::FleetExposure;
using internal::InsertFailureRecord;
using internal::LoadModes;
using internal::LoadReport;
using internal::LoadUnitType;
using internal::Micros;
using internal::RefineModeSignature;
using internal::SettingsFor;
using internal::UnitTypeId;

absl::StatusOr<StoredDiagnosis> LoadDiagnosis(Connection& db, const std::string& id) {
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows,
      db.Exec("SELECT d.body, coalesce(d.record_id::text, ''), coalesce(r.confirmed, false), "
              "coalesce(m.role, '') "
              "FROM diagnoses d LEFT JOIN failure_records r ON r.record_id = d.record_id "
              "LEFT JOIN modules m ON m.module_id = r.module_id WHERE d.diagnosis_id = $1::uuid",
              {Param::Text(id)}, ResultFormat::kBinary));
  if (rows.rows() == 0)
    return absl::NotFoundError(
        absl::StrCat(api::ResourceName(api::kDiagnoses, id), " does not exist"));
  StoredDiagnosis d;
  d.name = api::ResourceName(api::kDiagnoses, id);
  d.encoded = std::string(rows.Get(0, 0));
  if (!rows.Get(0, 1).empty()) {
    d.failure_record = api::ResourceName(api::kFailureRecords, rows.String(0, 1));
    d.confirmed = rows.Get(0, 2) == std::string_view("\x01", 1);
    d.resolved_module = rows.String(0, 3);
  }
  return d;
}

// The unit's own significant trends, over its runs up to this analysis's
// (this analysis standing for its run), as evidence (kb/unit_history.h).
absl::Status LoadHistoryEvidence(Connection& db, DiagnosisInputs& in) {
  internal::HistoryScope scope;
  scope.unit_id = in.unit_id;
  scope.until_analysis_id = in.analysis_id;
  INSDIAG_ASSIGN_OR_RETURN(auto history,
                           internal::LoadParameterHistories(db, scope, HistoryOptions()));
  std::vector<EvidenceTerm> trends = TrendEvidence(history, in.settings);
  int runs = 0;
  for (const auto& p : history) runs = std::max(runs, p.statistics.count);
  if (runs < 3) return absl::OkStatus();  // no trend to test yet
  std::vector<std::string> names;
  for (const auto& t : trends) names.push_back(t.trend_of);
  in.history_note =
      trends.empty() ? absl::StrCat("the unit's history (", runs, " runs): no parameter trends significantly")
                     : absl::StrCat("the unit's history (", runs, " runs): significant trends in ",
                                    absl::StrJoin(names, ", "));
  in.history_trends = std::move(trends);
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<DiagnosisInputs> DiagnosisStore::LoadInputs(const std::string& analysis_name) {
  DiagnosisInputs in;
  in.analysis_name = analysis_name;
  INSDIAG_ASSIGN_OR_RETURN(in.analysis_id, internal::UuidOf(analysis_name, api::kAnalyses, "analysis"));
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  INSDIAG_ASSIGN_OR_RETURN(
      auto unit,
      db->Exec(
          "SELECT a.unit_id, u.serial, coalesce(u.unit_type, ''), coalesce(a.unit_hours, "
          "u.operating_hours), "
          "coalesce((SELECT max(p.unit_hours) FROM analyses p WHERE p.unit_id = a.unit_id AND "
          "p.state = 'SUCCEEDED' "
          "AND p.create_time < a.create_time), 0) "
          "FROM analyses a JOIN units u ON u.unit_id = a.unit_id WHERE a.analysis_id = $1::uuid",
          {Param::Text(in.analysis_id)}));
  if (unit.rows() == 0) return absl::NotFoundError(absl::StrCat(analysis_name, " does not exist"));
  in.unit_id = unit.String(0, 0);
  in.serial = unit.String(0, 1);
  const std::string type_id = unit.String(0, 2);
  if (type_id.empty()) {
    return absl::FailedPreconditionError(absl::StrCat(
        api::ResourceName(api::kUnits, in.serial), " has no unit type (its runs name none): ",
        "there is no nominal model to diagnose against"));
  }
  INSDIAG_ASSIGN_OR_RETURN(const StoredReport report, LoadReport(*db, in.analysis_id));
  INSDIAG_ASSIGN_OR_RETURN(in.report, ReportFindingsOf(report, decode_report_));
  auto unit_type = LoadUnitType(*db, type_id);
  if (!unit_type.ok()) {
    if (unit_type.status().code() == absl::StatusCode::kNotFound) {
      return absl::FailedPreconditionError(
          absl::StrCat(api::ResourceName(api::kUnits, in.serial), " is of unit type '", type_id,
                       "', which the knowledge base does not know"));
    }
    return unit_type.status();
  }
  in.unit_type = *std::move(unit_type);
  INSDIAG_ASSIGN_OR_RETURN(in.modes, LoadModes(*db, type_id, "", ""));
  INSDIAG_ASSIGN_OR_RETURN(auto fleet, FleetExposure(*db, type_id));
  INSDIAG_ASSIGN_OR_RETURN(auto type_settings, SettingsFor(*db, type_id));
  in.settings = type_settings.settings;
  in.settings_note = type_settings.note;
  const double hours = internal::DoubleOr0(unit, 0, 3);
  const double previous = internal::DoubleOr0(unit, 0, 4);
  in.prior.exposure_hours = std::max(hours - previous, 0.0);
  in.prior.fleet_exposure_hours = fleet;
  for (const FailureMode& m : in.modes) in.prior.confirmed_failures[m.name] = m.confirmed_failures;
  INSDIAG_RETURN_IF_ERROR(LoadHistoryEvidence(*db, in));
  return in;
}


absl::StatusOr<StoredDiagnosis> DiagnosisStore::Store(const DiagnosisInputs& in, const Diagnosis& diagnosis,
                                                      const DiagnosisEncoder& encode) {
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  StoredDiagnosis stored;
  const absl::Status status = db->InTransaction([&]() -> absl::Status {
    INSDIAG_ASSIGN_OR_RETURN(auto made,
                             db->Exec("SELECT gen_random_uuid()::text, " + Micros("now()")));
    const std::string id = made.String(0, 0);
    const std::int64_t create_micros = internal::IntOr0(made, 0, 1);
    stored.name = api::ResourceName(api::kDiagnoses, id);
    stored.encoded = encode(diagnosis, stored.name, absl::FromUnixMicros(create_micros));
    const DiagnosisHeadline headline = HeadlineOf(diagnosis);
    const Candidate* top = headline.top;
    auto inserted = db->Exec(
        "INSERT INTO diagnoses (diagnosis_id, analysis_id, unit_id, fault_probability, top_module, "
        "top_failure_mode, "
        "top_probability, body, notes, create_time) VALUES ($1::uuid, $2::uuid, $3, $4, $5, $6, "
        "$7, $8, $9::text[], "
        "to_timestamp($10::double precision / 1000000))",
        {Param::Text(id), Param::Text(in.analysis_id), Param::Text(in.unit_id),
         Param::Double(headline.fault_probability), Param::Text(top ? top->module : ""),
         Param::Text(top ? top->failure_mode : ""), Param::Double(top ? top->probability : 0.0),
         Param::Bytes(stored.encoded), Param::TextArray(diagnosis.notes), Param::Int(create_micros)});
    if (!inserted.ok()) return inserted.status();
    int rank = 0;
    for (const Candidate& c : diagnosis.candidates) {
      INSDIAG_RETURN_IF_ERROR(
          db->Exec("INSERT INTO diagnosis_candidates (diagnosis_id, rank, module, "
                   "failure_mode, probability, evidence) "
                   "VALUES ($1::uuid, $2, $3, $4, $5, $6::text[])",
                   {Param::Text(id), Param::Int(rank++), Param::Text(c.module),
                    Param::Text(c.failure_mode), Param::Double(c.probability),
                    Param::TextArray(c.evidence)}));
    }
    return absl::OkStatus();
  });
  if (!status.ok()) return status;
  return stored;
}

absl::StatusOr<StoredDiagnosis> DiagnosisStore::Get(const std::string& name) {
  INSDIAG_ASSIGN_OR_RETURN(auto id, internal::UuidOf(name, api::kDiagnoses, "name"));
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  return LoadDiagnosis(*db, id);
}

absl::StatusOr<std::pair<std::vector<StoredDiagnosis>, std::string>> DiagnosisStore::List(
    const DiagnosisQuery& query) {
  const int size = internal::ClampPageSize(query.page.page_size);
  std::string analysis_id, serial;
  if (!query.analysis.empty()) {
    INSDIAG_ASSIGN_OR_RETURN(auto id, internal::UuidOf(query.analysis, api::kAnalyses, "analysis"));
    analysis_id = id;
  }
  if (!query.unit.empty()) {
    INSDIAG_ASSIGN_OR_RETURN(auto s, api::ResourceId(query.unit, api::kUnits, "unit"));
    serial = s;
  }
  std::vector<Param> params = {Param::Int(size + 1), Param::TextOrNull(analysis_id), Param::TextOrNull(serial)};
  INSDIAG_ASSIGN_OR_RETURN(auto after, internal::KeysetCondition(
                                           query.page.page_token, "d.create_time", "d.diagnosis_id",
                                           internal::KeysetOrder::kNewestFirst, params));
  INSDIAG_ASSIGN_OR_RETURN(auto db, list_pool_.Acquire());
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows,
      db->Exec(absl::StrCat("SELECT d.diagnosis_id::text, d.create_time::text FROM diagnoses d "
                            "JOIN units u USING (unit_id) "
                            "WHERE ($2::uuid IS NULL OR d.analysis_id = $2::uuid) AND ($3::text IS "
                            "NULL OR u.serial = $3) AND ",
                            after, " ORDER BY d.create_time DESC, d.diagnosis_id DESC LIMIT $1"),
               params));
  std::vector<StoredDiagnosis> out;
  const int shown = std::min(rows.rows(), size);
  for (int r = 0; r < shown; ++r) {
    INSDIAG_ASSIGN_OR_RETURN(auto d, LoadDiagnosis(*db, rows.String(r, 0)));
    out.push_back(std::move(d));
  }
  std::string next;
  if (rows.rows() > size)
    next = internal::EncodeToken(rows.String(shown - 1, 1), rows.String(shown - 1, 0));
  return std::make_pair(std::move(out), next);
}

absl::StatusOr<StoredDiagnosis> DiagnosisStore::Resolve(const DiagnosisResolution& request) {
  INSDIAG_ASSIGN_OR_RETURN(auto id, internal::UuidOf(request.name, api::kDiagnoses, "name"));
  if (request.module.empty()) {
    return absl::InvalidArgumentError("module: the module found faulty (or suspected) is required");
  }
  std::string mode_id;
  if (!request.failure_mode.empty()) {
    INSDIAG_ASSIGN_OR_RETURN(
        auto m, api::ResourceId(request.failure_mode, api::kFailureModes, "failure_mode"));
    mode_id = m;
  }
  if (request.confirmed && mode_id.empty()) {
    return absl::InvalidArgumentError("failure_mode: a confirmed diagnosis names the failure mode found");
  }
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  const absl::Status status = db->InTransaction([&]() -> absl::Status {
    INSDIAG_ASSIGN_OR_RETURN(auto row,
                             db->Exec("SELECT d.analysis_id::text, d.unit_id, d.record_id IS NOT "
                                      "NULL, coalesce(a.unit_hours, u.operating_hours) "
                                      "FROM diagnoses d JOIN analyses a USING (analysis_id) JOIN "
                                      "units u ON u.unit_id = d.unit_id "
                                      "WHERE d.diagnosis_id = $1::uuid FOR UPDATE OF d",
                                      {Param::Text(id)}));
    if (row.rows() == 0)
      return absl::NotFoundError(absl::StrCat(request.name, " does not exist"));
    if (row.Bool(0, 2))
      return absl::FailedPreconditionError(absl::StrCat(request.name, " is already resolved"));
    INSDIAG_ASSIGN_OR_RETURN(auto unit_id, row.Int(0, 1));
    INSDIAG_RETURN_IF_ERROR(CheckModuleRole(*db, request.module, "module"));
    if (auto fits = CheckModeOfRole(*db, mode_id, request.failure_mode, request.module, "failure_mode");
        !fits.ok()) {
      return fits;
    }
    INSDIAG_ASSIGN_OR_RETURN(auto module_id, CurrentModule(*db, unit_id, request.module));
    FailureRecord record;
    record.operating_hours = internal::DoubleOr0(row, 0, 3);
    record.confirmed = request.confirmed;
    record.no_fault_found = !request.confirmed;
    record.repaired = request.confirmed && !request.repair_action.empty();
    record.repair_action = request.repair_action;
    record.notes = request.notes;
    INSDIAG_ASSIGN_OR_RETURN(auto written, InsertFailureRecord(*db, module_id, unit_id, record,
                                                               mode_id, row.String(0, 0), id));
    INSDIAG_RETURN_IF_ERROR(
        db->Exec("UPDATE diagnoses SET record_id = $2::uuid WHERE diagnosis_id = $1::uuid",
                 {Param::Text(id), Param::Text(written)}));
    if (request.confirmed) return RefineModeSignature(*db, mode_id, decode_report_);
    return absl::OkStatus();
  });
  if (!status.ok()) return status;
  return LoadDiagnosis(*db, id);
}

absl::Status DiagnosisStore::RefineSignatures(const std::string& unit_type) {
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  INSDIAG_ASSIGN_OR_RETURN(
      auto modes, db->Exec("SELECT DISTINCT r.failure_mode FROM failure_records r JOIN "
                           "failure_modes f USING (failure_mode) "
                           "WHERE r.confirmed AND r.analysis_id IS NOT NULL AND ($1::text IS NULL "
                           "OR f.unit_type = $1) ORDER BY 1",
                           {Param::TextOrNull(unit_type.empty() ? "" : UnitTypeId(unit_type))}));
  for (int r = 0; r < modes.rows(); ++r) {
    const std::string mode_id = modes.String(r, 0);
    INSDIAG_RETURN_IF_ERROR(db->InTransaction([&] { return RefineModeSignature(*db, mode_id, decode_report_); }));
  }
  return absl::OkStatus();
}

}  // namespace insdiag::kb
