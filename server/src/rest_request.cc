#include "rest_request.h"

#include <absl/strings/numbers.h>
#include <absl/strings/str_cat.h>
#include <absl/strings/str_split.h>
#include <google/protobuf/descriptor.h>

#include "insdiag/api/json.h"
#include "insdiag/engine/status_macros.h"

// Last: httplib.h pulls in <resolv.h>, whose `_res` macro breaks Eigen's headers.
#include <httplib.h>

namespace insdiag::server {

using google::protobuf::FieldDescriptor;
using google::protobuf::Message;

static const FieldDescriptor* FindField(const google::protobuf::Descriptor* type, const std::string& name) {
  if (const auto* field = type->FindFieldByName(name)) return field;
  return type->FindFieldByCamelcaseName(name);  // the JSON spelling: pageSize
}

// Sets the scalar at dotted `path` (proto or JSON names) from its text, as
// path variables and query parameters carry it; repeated fields get an
// element added.
absl::Status SetFieldFromText(Message& message, const std::string& path, const std::string& text) {
  Message* target = &message;
  const std::vector<std::string> names = absl::StrSplit(path, '.');
  for (std::size_t i = 0; i < names.size(); ++i) {
    const FieldDescriptor* field = FindField(target->GetDescriptor(), names[i]);
    if (field == nullptr) {
      return absl::InvalidArgumentError(
          absl::StrCat("unknown parameter '", path, "' for ", message.GetDescriptor()->full_name()));
    }
    const auto* reflection = target->GetReflection();
    if (i + 1 < names.size()) {
      if (field->cpp_type() != FieldDescriptor::CPPTYPE_MESSAGE || field->is_repeated()) {
        return absl::InvalidArgumentError(absl::StrCat("parameter '", path, "' does not name a field"));
      }
      target = reflection->MutableMessage(target, field);
      continue;
    }
    const bool repeated = field->is_repeated();
    const auto bad = [&] {
      return absl::InvalidArgumentError(absl::StrCat("parameter '", path, "': '", text, "' is not a valid ",
                                                     field->cpp_type_name()));
    };
    switch (field->cpp_type()) {
      case FieldDescriptor::CPPTYPE_STRING:
        repeated ? reflection->AddString(target, field, text) : reflection->SetString(target, field, text);
        return absl::OkStatus();
      case FieldDescriptor::CPPTYPE_INT32:
      case FieldDescriptor::CPPTYPE_INT64: {
        std::int64_t value = 0;
        if (!absl::SimpleAtoi(text, &value)) return bad();
        if (field->cpp_type() == FieldDescriptor::CPPTYPE_INT32) {
          if (value < INT32_MIN || value > INT32_MAX) return bad();
          const auto narrow = static_cast<std::int32_t>(value);
          repeated ? reflection->AddInt32(target, field, narrow) : reflection->SetInt32(target, field, narrow);
        } else {
          repeated ? reflection->AddInt64(target, field, value) : reflection->SetInt64(target, field, value);
        }
        return absl::OkStatus();
      }
      case FieldDescriptor::CPPTYPE_UINT32:
      case FieldDescriptor::CPPTYPE_UINT64: {
        std::uint64_t value = 0;
        if (!absl::SimpleAtoi(text, &value)) return bad();
        if (field->cpp_type() == FieldDescriptor::CPPTYPE_UINT32) {
          if (value > UINT32_MAX) return bad();
          const auto narrow = static_cast<std::uint32_t>(value);
          repeated ? reflection->AddUInt32(target, field, narrow) : reflection->SetUInt32(target, field, narrow);
        } else {
          repeated ? reflection->AddUInt64(target, field, value) : reflection->SetUInt64(target, field, value);
        }
        return absl::OkStatus();
      }
      case FieldDescriptor::CPPTYPE_DOUBLE:
      case FieldDescriptor::CPPTYPE_FLOAT: {
        double value = 0;
        if (!absl::SimpleAtod(text, &value)) return bad();
        if (field->cpp_type() == FieldDescriptor::CPPTYPE_FLOAT) {
          const auto narrow = static_cast<float>(value);
          repeated ? reflection->AddFloat(target, field, narrow) : reflection->SetFloat(target, field, narrow);
        } else {
          repeated ? reflection->AddDouble(target, field, value) : reflection->SetDouble(target, field, value);
        }
        return absl::OkStatus();
      }
      case FieldDescriptor::CPPTYPE_BOOL: {
        if (text != "true" && text != "false") return bad();
        repeated ? reflection->AddBool(target, field, text == "true")
                 : reflection->SetBool(target, field, text == "true");
        return absl::OkStatus();
      }
      case FieldDescriptor::CPPTYPE_ENUM: {
        const auto* value = field->enum_type()->FindValueByName(text);
        int number = 0;
        if (value == nullptr && absl::SimpleAtoi(text, &number)) value = field->enum_type()->FindValueByNumber(number);
        if (value == nullptr) return bad();
        repeated ? reflection->AddEnum(target, field, value) : reflection->SetEnum(target, field, value);
        return absl::OkStatus();
      }
      case FieldDescriptor::CPPTYPE_MESSAGE:
        return absl::InvalidArgumentError(
            absl::StrCat("parameter '", path, "' names a message; send it in the JSON body"));
    }
  }
  return absl::InvalidArgumentError(absl::StrCat("empty parameter name"));
}

// The request message of a non-streaming-request method from the HTTP request.
absl::Status BuildRequest(const std::string& body_rule, const std::map<std::string, std::string>& bindings,
                          const httplib::Request& http, Message& request) {
  if (!body_rule.empty() && !http.body.empty()) {
    Message* body_target = &request;
    if (body_rule != "*") {
      const FieldDescriptor* field = request.GetDescriptor()->FindFieldByName(body_rule);
      if (field == nullptr || field->cpp_type() != FieldDescriptor::CPPTYPE_MESSAGE) {
        return absl::InternalError(absl::StrCat("http rule body '", body_rule, "' names no message field"));
      }
      body_target = request.GetReflection()->MutableMessage(&request, field);
    }
    INSDIAG_RETURN_IF_ERROR(api::FromJson(http.body, body_target));
  }
  for (const auto& [name, value] : http.params) {
    INSDIAG_RETURN_IF_ERROR(SetFieldFromText(request, name, value));
  }
  // Path variables last: the URL names the resource, whatever the body says.
  for (const auto& [path, value] : bindings) {
    const FieldDescriptor* field = FindField(request.GetDescriptor(), path);
    if (field != nullptr && !field->is_repeated() && field->cpp_type() == FieldDescriptor::CPPTYPE_STRING) {
      request.GetReflection()->ClearField(&request, field);
    }
    INSDIAG_RETURN_IF_ERROR(SetFieldFromText(request, path, value));
  }
  return absl::OkStatus();
}

}  // namespace insdiag::server
