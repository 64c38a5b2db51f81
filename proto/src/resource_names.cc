#include "insdiag/api/resource_names.h"

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
    // Debian's abseil has its own string_view: the message is put together here.
    std::string message(field);
    for (std::string_view part : {std::string_view(": '"), name, std::string_view("' is not "), collection.noun,
                                  std::string_view(" name ("), collection.segment, std::string_view("/{"), collection.id,
                                  std::string_view("})")}) {
      message += part;
    }
    return absl::InvalidArgumentError(message);
  }
  return std::string(id);
}

std::string IdOrSelf(std::string_view name, const Collection& collection) {
  const std::string_view id = IdAfterSegment(name, collection);
  return std::string(id.empty() ? name : id);
}

}  // namespace insdiag::api
