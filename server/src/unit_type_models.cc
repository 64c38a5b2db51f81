#include "insdiag/server/unit_type_models.h"

#include <string>

#include "insdiag/api/resource_names.h"
#include "insdiag/api/unit_types.h"
#include "insdiag/kb/catalogue_store.h"
#include "insdiag/kb/knowledge_messages.h"

namespace insdiag::server {

absl::StatusOr<std::optional<engine::ErrorModel>> NominalModelOfUnitType(kb::ConnectionPool& pool,
                                                                         std::string_view unit_type) {
  if (unit_type.empty()) return std::nullopt;
  kb::CatalogueStore catalogue(pool);
  auto found = catalogue.GetUnitType(api::ResourceName(api::kUnitTypes, unit_type));
  if (!found.ok()) {
    const auto code = found.status().code();
    if (code == absl::StatusCode::kNotFound || code == absl::StatusCode::kInvalidArgument) return std::nullopt;
    return found.status();
  }
  auto nominal = api::BaseModelOf(kb::ToProto(*found));
  if (!nominal.ok()) return std::nullopt;
  return *std::move(nominal);
}

}  // namespace insdiag::server
