// A run's unit type's nominal model from the knowledge base: the a-priori
// model's second source after the run's datasheet (engine/analysis.h,
// APrioriModel), for the analysis workers and the live monitor alike.
#pragma once

#include <absl/status/statusor.h>

#include <optional>
#include <string_view>

#include "insdiag/engine/model/error_model.h"
#include "insdiag/kb/connection_pool.h"

namespace insdiag::server {

// Empty when `unit_type` is empty, unknown to the catalogue or not a valid
// name, or when its nominal values make no base model; an error only when the
// knowledge base does not answer.
absl::StatusOr<std::optional<engine::ErrorModel>> NominalModelOfUnitType(kb::ConnectionPool& pool,
                                                                         std::string_view unit_type);

}  // namespace insdiag::server
