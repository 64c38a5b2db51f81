// The unit types insdiag ships with (data/unit-types/*.json, built into the
// binaries): their nominal error-model parameters and tolerances. The
// knowledge base is seeded from them and `insdiag simulate` draws its default
// unit from them.
#pragma once

#include <absl/status/statusor.h>

#include <string_view>
#include <vector>

#include "insdiag/engine/model/error_model.h"
#include "insdiag/v1/knowledge.pb.h"

namespace insdiag::api {

std::vector<v1::UnitType> BuiltinUnitTypes();
// By display name ("INS-2000") or resource name ("unitTypes/INS-2000").
absl::StatusOr<v1::UnitType> BuiltinUnitType(std::string_view name);

// The base error model of a unit type: its drifts, noise densities and
// quantisation (its effects' nominal values are zero: they are tolerances for
// diagnosis, not model components).
absl::StatusOr<engine::ErrorModel> BaseModelOf(const v1::UnitType& unit_type);

}  // namespace insdiag::api
