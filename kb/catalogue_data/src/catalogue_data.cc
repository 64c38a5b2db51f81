#include "insdiag/kb/catalogue_data.h"

#include "insdiag/api/resource_names.h"
#include "insdiag/api/unit_types.h"
#include "insdiag/engine/status_macros.h"
#include "insdiag/kb/failure_mode_catalogue.h"
#include "insdiag/kb/knowledge_messages.h"

namespace insdiag::kb {
namespace {

absl::StatusOr<std::vector<FailureMode>> ExpandedModes(const v1::FailureModeCatalogue& catalogue) {
  INSDIAG_ASSIGN_OR_RETURN(const std::vector<v1::FailureMode> expanded, ExpandCatalogue(catalogue));
  std::vector<FailureMode> modes;
  modes.reserve(expanded.size());
  for (const v1::FailureMode& mode : expanded) modes.push_back(FailureModeOf(mode));
  return modes;
}

}  // namespace

absl::StatusOr<CatalogueData> BuiltinCatalogueData() {
  CatalogueData data;
  for (const v1::UnitType& unit_type : api::BuiltinUnitTypes()) data.unit_types.push_back(UnitTypeOf(unit_type));
  for (const v1::FailureModeCatalogue& catalogue : BuiltinFailureModeCatalogues()) {
    INSDIAG_ASSIGN_OR_RETURN(std::vector<FailureMode> modes, ExpandedModes(catalogue));
    for (FailureMode& mode : modes) data.failure_modes.push_back(std::move(mode));
    data.settings.push_back(UnitTypeDiagnosisSettings{api::ResourceName(api::kUnitTypes, catalogue.unit_type()),
                                                      SettingsOf(catalogue.settings())});
  }
  return data;
}

absl::StatusOr<UnitTypeCatalogue> BuiltinUnitTypeCatalogue(const std::string& unit_type) {
  INSDIAG_ASSIGN_OR_RETURN(const v1::UnitType type, api::BuiltinUnitType(unit_type));
  UnitTypeCatalogue out;
  out.unit_type = UnitTypeOf(type);
  INSDIAG_ASSIGN_OR_RETURN(const v1::FailureModeCatalogue* catalogue,
                           BuiltinFailureModeCatalogue(api::IdOrSelf(out.unit_type.name, api::kUnitTypes)));
  INSDIAG_ASSIGN_OR_RETURN(out.failure_modes, ExpandedModes(*catalogue));
  out.settings = SettingsOf(catalogue->settings());
  return out;
}

absl::Status SeedBuiltinCatalogues(CatalogueStore& store) {
  INSDIAG_ASSIGN_OR_RETURN(const CatalogueData data, BuiltinCatalogueData());
  return store.Seed(data.unit_types, data.failure_modes, data.settings);
}

}  // namespace insdiag::kb
