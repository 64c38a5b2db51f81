#include "insdiag/kb/failure_record_store.h"

#include <absl/strings/match.h>
#include <absl/strings/str_cat.h>
#include <absl/time/time.h>

#include <algorithm>

#include "catalogue_rows.h"
#include "failure_record_writes.h"
#include "insdiag/api/resource_names.h"
#include "insdiag/engine/status_macros.h"
#include "signature_refinement.h"
#include "store_util.h"

namespace insdiag::kb {
namespace {

using internal::BoolText;
using internal::CheckModeOfRole;
using internal::CheckModuleRole;
using internal::CurrentModule;
using internal::InsertFailureRecord;
using internal::Micros;
using internal::RefineModeSignature;

constexpr char kRecordColumns[] =
    "SELECT r.record_id::text, u.serial, m.role, coalesce(r.failure_mode, ''), coalesce(r.analysis_id::text, ''), "
    "r.operating_hours, r.confirmed, r.repaired, r.censored, (extract(epoch FROM r.record_time) * 1000000)::bigint, "
    "r.no_fault_found, r.repair_action, (extract(epoch FROM r.detected_time) * 1000000)::bigint, "
    "coalesce(r.diagnosis_id::text, ''), r.notes, r.record_time::text, r.revision "
    "FROM failure_records r JOIN modules m USING (module_id) JOIN units u ON u.unit_id = r.unit_id ";

FailureRecord RecordFromRow(const Result& rows, int r) {
  FailureRecord f;
  f.name = api::ResourceName(api::kFailureRecords, rows.String(r, 0));
  f.module = api::ModuleName(rows.String(r, 1), rows.String(r, 2));
  if (!rows.String(r, 3).empty()) f.failure_mode = api::ResourceName(api::kFailureModes, rows.String(r, 3));
  if (!rows.String(r, 4).empty()) f.analysis = api::ResourceName(api::kAnalyses, rows.String(r, 4));
  f.operating_hours = internal::DoubleOr0(rows, r, 5);
  f.confirmed = rows.Bool(r, 6);
  f.repaired = rows.Bool(r, 7);
  f.censored = rows.Bool(r, 8);
  f.record_time = absl::FromUnixMicros(internal::IntOr0(rows, r, 9));
  f.no_fault_found = rows.Bool(r, 10);
  f.repair_action = rows.String(r, 11);
  f.detected_time = absl::FromUnixMicros(internal::IntOr0(rows, r, 12));
  if (!rows.String(r, 13).empty()) f.diagnosis = api::ResourceName(api::kDiagnoses, rows.String(r, 13));
  f.notes = rows.String(r, 14);
  f.revision = static_cast<int>(internal::IntOr0(rows, r, 16));
  return f;
}

// A record's facts, checked before any database work: its failure mode's id
// ("" for none), or INVALID_ARGUMENT naming the field.
absl::StatusOr<std::string> CheckedFacts(const FailureRecord& facts) {
  std::string mode_id;
  if (!facts.failure_mode.empty()) {
    auto id = api::ResourceId(facts.failure_mode, api::kFailureModes, "failure_record.failure_mode");
    if (!id.ok()) return id.status();
    mode_id = *id;
  }
  if (facts.confirmed && mode_id.empty()) {
    return absl::InvalidArgumentError("failure_record.failure_mode: a confirmed failure names its failure mode");
  }
  if (facts.confirmed && facts.no_fault_found) {
    return absl::InvalidArgumentError("failure_record.no_fault_found: a confirmed failure cannot be no-fault-found");
  }
  if (!(facts.operating_hours >= 0)) {
    return absl::InvalidArgumentError("failure_record.operating_hours: must be 0 or more");
  }
  return mode_id;
}

absl::StatusOr<FailureRecord> GetRecord(Connection& db, const std::string& id) {
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows,
      db.Exec(absl::StrCat(kRecordColumns, "WHERE r.record_id = $1::uuid"), {Param::Text(id)}));
  if (rows.rows() == 0)
    return absl::NotFoundError(
        absl::StrCat(api::ResourceName(api::kFailureRecords, id), " does not exist"));
  return RecordFromRow(rows, 0);
}

}  // namespace

absl::StatusOr<FailureRecord> FailureRecordStore::Create(const FailureRecord& record) {
  INSDIAG_ASSIGN_OR_RETURN(auto module, api::ParseModuleName(record.module, "failure_record.module"));
  const std::string& serial = module.unit;
  const std::string& role = module.role;
  INSDIAG_ASSIGN_OR_RETURN(auto checked_mode, CheckedFacts(record));
  const std::string mode_id = checked_mode;
  std::string analysis_id;
  if (!record.analysis.empty()) {
    INSDIAG_ASSIGN_OR_RETURN(auto id, internal::UuidOf(record.analysis, api::kAnalyses, "failure_record.analysis"));
    analysis_id = id;
  }
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  std::string id;
  const absl::Status status = db->InTransaction([&]() -> absl::Status {
    INSDIAG_ASSIGN_OR_RETURN(
        auto unit, db->Exec("SELECT unit_id FROM units WHERE serial = $1", {Param::Text(serial)}));
    if (unit.rows() == 0) {
      return absl::NotFoundError(absl::StrCat("failure_record.module: units/", serial, " does not exist"));
    }
    INSDIAG_RETURN_IF_ERROR(CheckModuleRole(*db, role, "failure_record.module"));
    if (auto fits = CheckModeOfRole(*db, mode_id, record.failure_mode, role, "failure_record.failure_mode");
        !fits.ok()) {
      return fits;
    }
    INSDIAG_ASSIGN_OR_RETURN(auto unit_id, unit.Int(0, 0));
    INSDIAG_ASSIGN_OR_RETURN(auto module_id, CurrentModule(*db, unit_id, role));
    auto written = InsertFailureRecord(*db, module_id, unit_id, record, mode_id, analysis_id, "");
    if (!written.ok()) {
      if (written.status().code() == absl::StatusCode::kFailedPrecondition && !analysis_id.empty()) {
        return absl::NotFoundError(absl::StrCat("failure_record.analysis: ", record.analysis, " does not exist"));
      }
      return written.status();
    }
    id = *written;
    if (record.confirmed) return RefineModeSignature(*db, mode_id, decode_report_);
    return absl::OkStatus();
  });
  if (!status.ok()) return status;
  return GetRecord(*db, id);
}

absl::StatusOr<FailureRecord> FailureRecordStore::Correct(const std::string& name, const FailureRecord& facts,
                                                          const std::string& reason) {
  INSDIAG_ASSIGN_OR_RETURN(auto id, internal::UuidOf(name, api::kFailureRecords, "name"));
  if (reason.empty()) return absl::InvalidArgumentError("reason: required (why the record was wrong)");
  INSDIAG_ASSIGN_OR_RETURN(auto checked_mode, CheckedFacts(facts));
  const std::string mode_id = checked_mode;
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  const absl::Status status = db->InTransaction([&]() -> absl::Status {
    INSDIAG_ASSIGN_OR_RETURN(
        auto current, db->Exec("SELECT coalesce(r.failure_mode, ''), m.role, r.confirmed FROM "
                               "failure_records r JOIN modules m "
                               "USING (module_id) WHERE r.record_id = $1::uuid FOR UPDATE OF r",
                               {Param::Text(id)}));
    if (current.rows() == 0) return absl::NotFoundError(absl::StrCat(name, " does not exist"));
    const std::string old_mode = current.String(0, 0), role = current.String(0, 1);
    const bool was_confirmed = current.Bool(0, 2);
    if (auto fits = CheckModeOfRole(*db, mode_id, facts.failure_mode, role, "failure_record.failure_mode");
        !fits.ok()) {
      return fits;
    }
    INSDIAG_RETURN_IF_ERROR(
        db->Exec("INSERT INTO failure_record_revisions (record_id, revision, "
                 "failure_mode, detected_time, operating_hours, "
                 "confirmed, no_fault_found, censored, repaired, "
                 "repair_action, notes, record_time, reason) "
                 "SELECT record_id, revision, failure_mode, detected_time, "
                 "operating_hours, confirmed, no_fault_found, "
                 "censored, repaired, repair_action, notes, record_time, $2 "
                 "FROM failure_records WHERE record_id = $1::uuid",
                 {Param::Text(id), Param::Text(reason)}));
    auto updated = db->Exec(
        "UPDATE failure_records SET failure_mode = $2, operating_hours = $3, confirmed = $4, "
        "no_fault_found = $5, "
        "censored = $6, repaired = $7, repair_action = $8, notes = $9, "
        "detected_time = coalesce($10::timestamptz, detected_time), record_time = now(), revision "
        "= revision + 1 "
        "WHERE record_id = $1::uuid",
        {Param::Text(id), Param::TextOrNull(mode_id), Param::Double(facts.operating_hours),
         Param::Text(BoolText(facts.confirmed)), Param::Text(BoolText(facts.no_fault_found)),
         Param::Text(BoolText(facts.censored)), Param::Text(BoolText(facts.repaired)),
         Param::Text(facts.repair_action), Param::Text(facts.notes),
         facts.detected_time.has_value() ? Param::Text(internal::TimeText(*facts.detected_time)) : Param::Null()});
    if (!updated.ok()) return updated.status();
    // The signatures learn from confirmed cases: a mode the record leaves or joins is refined again.
    if (was_confirmed && !old_mode.empty()) {
      INSDIAG_RETURN_IF_ERROR(RefineModeSignature(*db, old_mode, decode_report_));
    }
    if (facts.confirmed && mode_id != old_mode) return RefineModeSignature(*db, mode_id, decode_report_);
    return absl::OkStatus();
  });
  if (!status.ok()) return status;
  return GetRecord(*db, id);
}

absl::StatusOr<std::vector<FailureRecordRevision>> FailureRecordStore::ListRevisions(
    const std::string& name) {
  INSDIAG_ASSIGN_OR_RETURN(auto id, internal::UuidOf(name, api::kFailureRecords, "name"));
  INSDIAG_ASSIGN_OR_RETURN(auto db, list_pool_.Acquire());
  INSDIAG_ASSIGN_OR_RETURN(auto current, GetRecord(*db, id));
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows,
      db->Exec(absl::StrCat("SELECT revision, coalesce(failure_mode, ''), operating_hours, "
                            "confirmed, no_fault_found, censored, "
                            "repaired, repair_action, notes, ",
                            Micros("detected_time"), ", ", Micros("record_time"), ", ",
                            Micros("superseded_time"),
                            ", reason FROM failure_record_revisions WHERE record_id = $1::uuid "
                            "ORDER BY revision"),
               {Param::Text(id)}));
  std::vector<FailureRecordRevision> revisions;
  for (int r = 0; r < rows.rows(); ++r) {
    FailureRecordRevision& v = revisions.emplace_back();
    FailureRecord& f = v.failure_record;
    f = current;  // name, module, analysis and diagnosis do not change
    f.revision = static_cast<int>(internal::IntOr0(rows, r, 0));
    f.failure_mode.clear();
    if (!rows.String(r, 1).empty()) f.failure_mode = api::ResourceName(api::kFailureModes, rows.String(r, 1));
    f.operating_hours = internal::DoubleOr0(rows, r, 2);
    f.confirmed = rows.Bool(r, 3);
    f.no_fault_found = rows.Bool(r, 4);
    f.censored = rows.Bool(r, 5);
    f.repaired = rows.Bool(r, 6);
    f.repair_action = rows.String(r, 7);
    f.notes = rows.String(r, 8);
    f.detected_time = absl::FromUnixMicros(internal::IntOr0(rows, r, 9));
    f.record_time = absl::FromUnixMicros(internal::IntOr0(rows, r, 10));
    v.superseded_time = absl::FromUnixMicros(internal::IntOr0(rows, r, 11));
    v.reason = rows.String(r, 12);
  }
  return revisions;
}

absl::StatusOr<std::pair<std::vector<FailureRecord>, std::string>> FailureRecordStore::List(
    const FailureRecordQuery& query) {
  const int size = internal::ClampPageSize(query.page.page_size);
  std::string serial, role, mode_id;
  if (!query.module.empty()) {
    INSDIAG_ASSIGN_OR_RETURN(auto module, api::ParseModuleName(query.module, "module"));
    serial = module.unit;
    role = module.role;
  }
  if (!query.unit.empty()) {
    INSDIAG_ASSIGN_OR_RETURN(auto s, api::ResourceId(query.unit, api::kUnits, "unit"));
    serial = s;
  }
  if (!query.failure_mode.empty()) {
    INSDIAG_ASSIGN_OR_RETURN(
        auto m, api::ResourceId(query.failure_mode, api::kFailureModes, "failure_mode"));
    mode_id = m;
  }
  std::vector<Param> params = {Param::Int(size + 1), Param::TextOrNull(serial), Param::TextOrNull(role),
                               Param::TextOrNull(mode_id)};
  INSDIAG_ASSIGN_OR_RETURN(
      auto after, internal::KeysetCondition(query.page.page_token, "r.record_time", "r.record_id",
                                            internal::KeysetOrder::kNewestFirst, params));
  INSDIAG_ASSIGN_OR_RETURN(auto db, list_pool_.Acquire());
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows,
      db->Exec(
          absl::StrCat(
              kRecordColumns,
              "WHERE ($2::text IS NULL OR u.serial = $2) AND ($3::text IS NULL OR m.role = $3) "
              "AND ($4::text IS NULL OR r.failure_mode = $4) AND ",
              after, " ORDER BY r.record_time DESC, r.record_id DESC LIMIT $1"),
          params));
  std::vector<FailureRecord> out;
  const int shown = std::min(rows.rows(), size);
  for (int r = 0; r < shown; ++r) out.push_back(RecordFromRow(rows, r));
  std::string next;
  if (rows.rows() > size)
    next = internal::EncodeToken(rows.String(shown - 1, 15), rows.String(shown - 1, 0));
  return std::make_pair(std::move(out), next);
}

}  // namespace insdiag::kb
