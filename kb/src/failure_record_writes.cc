#include "failure_record_writes.h"

#include <absl/strings/str_cat.h>

#include "insdiag/engine/status_macros.h"
#include "store_util.h"

namespace insdiag::kb::internal {

absl::Status CheckModuleRole(Connection& db, const std::string& role, const std::string& field) {
  INSDIAG_ASSIGN_OR_RETURN(
      auto roles, db.Exec("SELECT 1 FROM module_roles WHERE role = $1", {Param::Text(role)}));
  if (roles.rows() == 0)
    return absl::InvalidArgumentError(absl::StrCat(field, ": '", role, "' is not a module role"));
  return absl::OkStatus();
}

absl::Status CheckModeOfRole(Connection& db, const std::string& mode_id, const std::string& mode_name,
                             const std::string& role, const std::string& field) {
  if (mode_id.empty()) return absl::OkStatus();
  INSDIAG_ASSIGN_OR_RETURN(auto mode,
                           db.Exec("SELECT module_role FROM failure_modes WHERE failure_mode = $1",
                                   {Param::Text(mode_id)}));
  if (mode.rows() == 0)
    return absl::NotFoundError(absl::StrCat(field, ": ", mode_name, " does not exist"));
  if (mode.String(0, 0) != role) {
    return absl::InvalidArgumentError(absl::StrCat(field, ": ", mode_name, " is a failure of ",
                                                   mode.String(0, 0), ", not of ", role));
  }
  return absl::OkStatus();
}

absl::StatusOr<std::int64_t> CurrentModule(Connection& db, std::int64_t unit_id, const std::string& role) {
  INSDIAG_ASSIGN_OR_RETURN(
      auto ensured,
      db.Exec("INSERT INTO modules (unit_id, role, installed_time) "
              "SELECT u.unit_id, r.role, u.create_time FROM units u CROSS JOIN module_roles r "
              "WHERE u.unit_id = $1 AND NOT EXISTS (SELECT 1 FROM modules m WHERE m.unit_id = "
              "u.unit_id "
              "AND m.role = r.role AND m.removed_time IS NULL)",
              {Param::Int(unit_id)}));
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows,
      db.Exec(
          "SELECT module_id FROM modules WHERE unit_id = $1 AND role = $2 AND removed_time IS NULL",
          {Param::Int(unit_id), Param::Text(role)}));
  if (rows.rows() == 0)
    return absl::InvalidArgumentError(absl::StrCat("module: '", role, "' is not a module role"));
  return rows.Int(0, 0);
}

absl::StatusOr<std::string> InsertFailureRecord(Connection& db, std::int64_t module_id, std::int64_t unit_id,
                                                const FailureRecord& f, const std::string& mode_id,
                                                const std::string& analysis_id, const std::string& diagnosis_id) {
  auto rows = db.Exec(
      "INSERT INTO failure_records (module_id, unit_id, failure_mode, analysis_id, diagnosis_id, detected_time, "
      "operating_hours, confirmed, no_fault_found, censored, repaired, repair_action, notes) "
      "VALUES ($1, $2, $3, $4::uuid, $5::uuid, coalesce($6::timestamptz, now()), $7, $8, $9, $10, $11, $12, $13) "
      "RETURNING record_id::text",
      {Param::Int(module_id), Param::Int(unit_id), Param::TextOrNull(mode_id), Param::TextOrNull(analysis_id),
       Param::TextOrNull(diagnosis_id),
       f.detected_time.has_value() ? Param::Text(TimeText(*f.detected_time)) : Param::Null(),
       Param::Double(f.operating_hours), Param::Text(BoolText(f.confirmed)),
       Param::Text(BoolText(f.no_fault_found)), Param::Text(BoolText(f.censored)),
       Param::Text(BoolText(f.repaired)), Param::Text(f.repair_action), Param::Text(f.notes)});
  if (!rows.ok()) return rows.status();
  return rows->String(0, 0);
}

}  // namespace insdiag::kb::internal
