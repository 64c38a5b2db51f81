// Writing a failure record: the checks and the insert that recording a
// failure and resolving a diagnosis share. Each runs inside its caller's
// transaction.
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <cstdint>
#include <string>

#include "insdiag/kb/failure_record.h"
#include "insdiag/kb/pg.h"

namespace insdiag::kb::internal {

// `role` is a module role; INVALID_ARGUMENT naming `field` otherwise.
absl::Status CheckModuleRole(Connection& db, const std::string& role, const std::string& field);

// The failure mode `mode_id` (named `mode_name` by the caller, in `field`)
// exists and is a failure of module role `role`; "" passes. NOT_FOUND or
// INVALID_ARGUMENT naming the field otherwise.
absl::Status CheckModeOfRole(Connection& db, const std::string& mode_id, const std::string& mode_name,
                             const std::string& role, const std::string& field);

// The current module of `role` in unit `unit_id` (registering the unit's
// modules when it has none yet).
absl::StatusOr<std::int64_t> CurrentModule(Connection& db, std::int64_t unit_id, const std::string& role);

// Inserts a checked record's facts and returns its id; "" for no mode,
// analysis or diagnosis.
absl::StatusOr<std::string> InsertFailureRecord(Connection& db, std::int64_t module_id, std::int64_t unit_id,
                                                const FailureRecord& f, const std::string& mode_id,
                                                const std::string& analysis_id, const std::string& diagnosis_id);

}  // namespace insdiag::kb::internal
