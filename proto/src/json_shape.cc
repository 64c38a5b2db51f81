#include "json_shape.h"

#include <absl/strings/str_cat.h>

namespace insdiag::api::internal {
namespace {

using google::protobuf::Descriptor;
using google::protobuf::FieldDescriptor;
using google::protobuf::Value;

const char* KindName(const Value& value) {
  switch (value.kind_case()) {
    case Value::kNullValue: return "null";
    case Value::kNumberValue: return "a number";
    case Value::kStringValue: return "a string";
    case Value::kBoolValue: return "a boolean";
    case Value::kStructValue: return "an object";
    case Value::kListValue: return "an array";
    default: return "nothing";
  }
}

absl::Status WrongType(const std::string& path, const char* expected, const Value& value) {
  return absl::InvalidArgumentError(
      absl::StrCat(path, ": expected ", expected, ", got ", KindName(value)));
}

// The JSON form of a well-known message type, when it is not an object.
enum class WellKnownForm { kObject, kString, kAnything, kWrapper };

WellKnownForm FormOf(const Descriptor& type) {
  const std::string& name = type.full_name();
  if (name == "google.protobuf.Timestamp" || name == "google.protobuf.Duration" ||
      name == "google.protobuf.FieldMask") {
    return WellKnownForm::kString;
  }
  if (name == "google.protobuf.Value" || name == "google.protobuf.Struct" || name == "google.protobuf.ListValue" ||
      name == "google.protobuf.Any") {
    return WellKnownForm::kAnything;  // protobuf's parser checks these itself
  }
  if (type.file()->name() == "google/protobuf/wrappers.proto") return WellKnownForm::kWrapper;
  return WellKnownForm::kObject;
}

absl::Status CheckSingle(const Value& value, const FieldDescriptor& field, const std::string& path);

absl::Status CheckScalar(const Value& value, FieldDescriptor::CppType type, const std::string& path) {
  switch (type) {
    case FieldDescriptor::CPPTYPE_BOOL:
      if (value.kind_case() != Value::kBoolValue) return WrongType(path, "true or false", value);
      return absl::OkStatus();
    case FieldDescriptor::CPPTYPE_STRING:
      if (value.kind_case() != Value::kStringValue) return WrongType(path, "a string", value);
      // PostgreSQL's text cannot hold U+0000, and no field of insdiag's means it.
      if (value.string_value().find('\0') != std::string::npos) {
        return absl::InvalidArgumentError(absl::StrCat(path, ": the string holds U+0000, which no text field takes"));
      }
      return absl::OkStatus();
    case FieldDescriptor::CPPTYPE_ENUM:
      if (value.kind_case() != Value::kStringValue && value.kind_case() != Value::kNumberValue) {
        return WrongType(path, "an enum value's name", value);
      }
      return absl::OkStatus();
    default:  // the numbers
      if (value.kind_case() != Value::kStringValue && value.kind_case() != Value::kNumberValue) {
        return WrongType(path, "a number", value);
      }
      return absl::OkStatus();
  }
}

absl::Status CheckMessage(const Value& value, const Descriptor& type, const std::string& path) {
  switch (FormOf(type)) {
    case WellKnownForm::kAnything: return absl::OkStatus();
    case WellKnownForm::kString:
      if (value.kind_case() != Value::kStringValue) return WrongType(path, "a string", value);
      return absl::OkStatus();
    case WellKnownForm::kWrapper: return CheckSingle(value, *type.FindFieldByName("value"), path);
    case WellKnownForm::kObject:
      if (value.kind_case() != Value::kStructValue) return WrongType(path, "an object", value);
      return CheckJsonShape(value.struct_value(), type, path);
  }
  return absl::OkStatus();
}

// One value of `field` (an element, when the field is a list).
absl::Status CheckSingle(const Value& value, const FieldDescriptor& field, const std::string& path) {
  if (value.kind_case() == Value::kNullValue) return absl::OkStatus();
  if (field.cpp_type() == FieldDescriptor::CPPTYPE_MESSAGE) return CheckMessage(value, *field.message_type(), path);
  return CheckScalar(value, field.cpp_type(), path);
}

absl::Status CheckField(const Value& value, const FieldDescriptor& field, const std::string& path) {
  if (value.kind_case() == Value::kNullValue) return absl::OkStatus();
  if (field.is_map()) {
    if (value.kind_case() != Value::kStructValue) return WrongType(path, "an object", value);
    const FieldDescriptor& mapped = *field.message_type()->FindFieldByName("value");
    for (const auto& [key, entry] : value.struct_value().fields()) {
      if (absl::Status status = CheckSingle(entry, mapped, absl::StrCat(path, "[\"", key, "\"]")); !status.ok()) {
        return status;
      }
    }
    return absl::OkStatus();
  }
  if (field.is_repeated()) {
    if (value.kind_case() != Value::kListValue) return WrongType(path, "an array", value);
    const auto& elements = value.list_value().values();
    for (int i = 0; i < elements.size(); ++i) {
      if (absl::Status status = CheckSingle(elements[i], field, absl::StrCat(path, "[", i, "]")); !status.ok()) {
        return status;
      }
    }
    return absl::OkStatus();
  }
  return CheckSingle(value, field, path);
}

}  // namespace

absl::Status CheckJsonShape(const google::protobuf::Struct& object, const Descriptor& type, const std::string& path) {
  for (const auto& [name, value] : object.fields()) {
    const FieldDescriptor* field = type.FindFieldByName(name);
    for (int i = 0; field == nullptr && i < type.field_count(); ++i) {
      if (type.field(i)->json_name() == name) field = type.field(i);
    }
    if (field == nullptr) continue;  // protobuf's parser names unknown fields
    const std::string field_path = path.empty() ? name : absl::StrCat(path, ".", name);
    if (absl::Status status = CheckField(value, *field, field_path); !status.ok()) return status;
  }
  return absl::OkStatus();
}

}  // namespace insdiag::api::internal
