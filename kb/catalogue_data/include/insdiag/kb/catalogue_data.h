// The expert catalogues built in (data/unit-types/*.json,
// data/failure-modes/*.json) in the knowledge base's own terms: the unit
// types with their nominal values, the failure modes expanded from their
// templates (signatures at the expert's values) and each unit type's
// diagnosis settings. What CatalogueStore::Seed takes, and what diagnosing
// offline reads.
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <string>
#include <vector>

#include "insdiag/kb/catalogue_store.h"
#include "insdiag/kb/knowledge.h"

namespace insdiag::kb {

struct CatalogueData {
  std::vector<UnitType> unit_types;
  std::vector<FailureMode> failure_modes;
  std::vector<UnitTypeDiagnosisSettings> settings;  // one per failure-mode catalogue
};

// Every built-in unit type and failure-mode catalogue; INVALID_ARGUMENT
// naming the mode and field for a malformed template.
absl::StatusOr<CatalogueData> BuiltinCatalogueData();

// One built-in unit type with its failure modes and diagnosis settings.
struct UnitTypeCatalogue {
  UnitType unit_type;
  std::vector<FailureMode> failure_modes;
  DiagnosisSettings settings;
};

// By display name ("INS-2000") or resource name; NOT_FOUND when the unit type
// or its failure-mode catalogue is not built in.
absl::StatusOr<UnitTypeCatalogue> BuiltinUnitTypeCatalogue(const std::string& unit_type);

// Seeds `store` with BuiltinCatalogueData().
absl::Status SeedBuiltinCatalogues(CatalogueStore& store);

}  // namespace insdiag::kb
