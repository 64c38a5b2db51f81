// Reading the catalogue's tables into messages: what the catalogue store
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

// The unit type whose built-in catalogue's diagnosis constants apply to a
// unit type that has no built-in catalogue (one made through the API).
inline constexpr char kDefaultSettingsUnitType[] = "INS-2000";

// The diagnosis constants a unit type is diagnosed with, and, when they are
// not its own, a note for the diagnosis that says whose they are.
struct UnitTypeSettings {
  DiagnosisSettings settings;
  std::string note;
};

// The diagnosis constants of the unit type's built-in catalogue, or
// kDefaultSettingsUnitType's with a note; FAILED_PRECONDITION when neither
// is built in.
absl::StatusOr<UnitTypeSettings> SettingsFor(const std::string& unit_type_id);

// The failure modes with their signatures, confirmed counts and current
// rates; each filter ("" for any) narrows: unit type, module role, one mode.
absl::StatusOr<std::vector<FailureMode>> LoadModes(Connection& db, const std::string& unit_type_id,
                                                       const std::string& role, const std::string& only_mode);

}  // namespace insdiag::kb::internal
