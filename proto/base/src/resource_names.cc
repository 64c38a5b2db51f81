#include "insdiag/api/resource_names.h"

#include <initializer_list>

namespace insdiag::api {
namespace {

// The id after "<segment>/", or empty when `name` does not start so.
std::string_view IdAfterSegment(std::string_view name, const Collection& collection) {
  if (name.size() <= collection.segment.size() || !name.starts_with(collection.segment) ||
      name[collection.segment.size()] != '/') {
    return {};
  }
  return name.substr(collection.segment.size() + 1);
}

// The refusal of `name` in `field`: "field: 'name'" and then `what`. Debian's
// abseil has its own string_view: the message is put together here.
absl::Status NotAName(std::string_view field, std::string_view name, std::initializer_list<std::string_view> what) {
  std::string message(field);
  message += ": '";
  message += name;
  for (std::string_view part : what) message += part;
  return absl::InvalidArgumentError(message);
}

}  // namespace

std::string ResourceName(const Collection& collection, std::string_view id) {
  std::string name(collection.segment);
  name += '/';
  name += id;
  return name;
}

absl::StatusOr<std::string> ResourceId(std::string_view name, const Collection& collection, std::string_view field) {
  const std::string_view id = IdAfterSegment(name, collection);
  if (id.empty() || id.find('/') != std::string_view::npos) {
    return NotAName(field, name, {"' is not ", collection.noun, " name (", collection.segment, "/{", collection.id, "})"});
  }
  return std::string(id);
}

namespace {
constexpr std::string_view kModulesSegment = "/modules/";
}  // namespace

std::string ModuleName(std::string_view unit_id, std::string_view role) {
  std::string name = ResourceName(kUnits, unit_id);
  name += kModulesSegment;
  name += role;
  return name;
}

absl::StatusOr<ModuleOfUnit> ParseModuleName(std::string_view name, std::string_view field) {
  const std::string_view after_unit = IdAfterSegment(name, kUnits);
  const std::size_t split = after_unit.find(kModulesSegment);
  if (split != std::string_view::npos && split > 0) {
    const std::string_view unit = after_unit.substr(0, split);
    const std::string_view role = after_unit.substr(split + kModulesSegment.size());
    if (unit.find('/') == std::string_view::npos && !role.empty() &&
        role.find('/') == std::string_view::npos) {
      return ModuleOfUnit{std::string(unit), std::string(role)};
    }
  }
  return NotAName(field, name, {"' is not a module name (units/{unit}/modules/{module})"});
}

std::string IdOrSelf(std::string_view name, const Collection& collection) {
  const std::string_view id = IdAfterSegment(name, collection);
  return std::string(id.empty() ? name : id);
}

}  // namespace insdiag::api
