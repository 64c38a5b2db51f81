// Reading the catalogue's tables into kb's values: what the catalogue store
// serves, and what diagnosing and refining signatures read alongside it.
#pragma once

#include <absl/status/statusor.h>

#include <string>
#include <vector>

#include "insdiag/kb/pg.h"
#include "insdiag/kb/knowledge.h"

namespace insdiag::kb::internal {

// unitTypes/{t} or a bare display name → {t}.
std::string UnitTypeId(const std::string& name);

// The unit type with its nominal values, in order; NOT_FOUND.
absl::StatusOr<UnitType> LoadUnitType(Connection& db, const std::string& id);

// The fleet's operating hours of a unit type.
absl::StatusOr<double> FleetExposure(Connection& db, const std::string& unit_type_id);

// The unit type whose diagnosis settings apply to a unit type that has none
// of its own (one whose catalogue is not built in, made through the API).
inline constexpr char kDefaultSettingsUnitType[] = "INS-2000";

// The columns of diagnosis_settings (migrations/0006_diagnosis_settings.sql)
// that hold a DiagnosisSettings, in its fields' order.
inline constexpr char kDiagnosisSettingsColumns[] =
    "healthy_tolerance_sd, healthy_log_ratio_fraction, healthy_z_sd, contamination, broad_log_ratio, "
    "broad_tolerance, broad_z, unknown_prior, minimum_exposure_hours, expert_pseudo_hours, "
    "expert_signature_weight, significance_level, incidental_contamination, trend_z_change, trend_z_spread, "
    "present_score_octaves";

// The diagnosis constants a unit type is diagnosed with, and, when they are
// not its own, a note for the diagnosis that says whose they are.
struct UnitTypeSettings {
  DiagnosisSettings settings;
  std::string note;
};

// The unit type's stored diagnosis settings, or kDefaultSettingsUnitType's
// with a note; FAILED_PRECONDITION when neither is stored.
absl::StatusOr<UnitTypeSettings> SettingsFor(Connection& db, const std::string& unit_type_id);

// The failure modes with their signatures, confirmed counts and current
// rates; each filter ("" for any) narrows: unit type, module role, one mode.
absl::StatusOr<std::vector<FailureMode>> LoadModes(Connection& db, const std::string& unit_type_id,
                                                       const std::string& role, const std::string& only_mode);

}  // namespace insdiag::kb::internal
