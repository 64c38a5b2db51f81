#include "insdiag/api/unit_types.h"

#include "insdiag/api/json.h"
#include "insdiag/engine/model/parameters.h"
#include "unit_type_data.h"

namespace insdiag::api {

std::vector<v1::UnitType> BuiltinUnitTypes() {
  std::vector<v1::UnitType> out;
  for (const std::string_view json : kUnitTypeJson) {
    v1::UnitType t;
    // The files are part of the build and parsed by a test; a broken one is a
    // build defect, not an input error.
    if (FromJson(json, &t).ok()) out.push_back(std::move(t));
  }
  return out;
}

absl::StatusOr<v1::UnitType> BuiltinUnitType(std::string_view name) {
  for (v1::UnitType& t : BuiltinUnitTypes()) {
    if (t.display_name() == name || t.name() == name) return t;
  }
  return absl::NotFoundError("no built-in unit type '" + std::string(name) + "'");
}

absl::StatusOr<engine::ErrorModel> BaseModelOf(const v1::UnitType& unit_type) {
  engine::ErrorModel model;
  for (const v1::NominalParameter& p : unit_type.nominal()) {
    engine::ErrorModel probe;
    if (!engine::SetParameter(p.name(), p.value(), probe).ok()) {
      return absl::InvalidArgumentError("unit type " + unit_type.name() + ": unknown parameter '" + p.name() + "'");
    }
    if (!probe.effects.empty()) continue;  // effects: tolerances, not model components
    if (auto st = engine::SetParameter(p.name(), p.value(), model); !st.ok()) return st;
  }
  return model;
}

}  // namespace insdiag::api
