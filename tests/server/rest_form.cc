#include "rest_form.h"

#include <absl/strings/str_cat.h>
#include <gtest/gtest.h>

#include <memory>
#include <regex>
#include <vector>

#include "google/api/annotations.pb.h"
#include "insdiag/api/json.h"

// Last: httplib.h pulls in <resolv.h>, whose `_res` macro breaks Eigen's headers.
#include <httplib.h>

namespace insdiag::testing {
namespace {

using google::protobuf::FieldDescriptor;
using google::protobuf::Message;
using google::protobuf::MethodDescriptor;

std::string QueryValue(const Message& message, const FieldDescriptor* field, int index) {
  const auto* r = message.GetReflection();
  const bool repeated = field->is_repeated();
  switch (field->cpp_type()) {
    case FieldDescriptor::CPPTYPE_STRING:
      return repeated ? r->GetRepeatedString(message, field, index) : r->GetString(message, field);
    case FieldDescriptor::CPPTYPE_INT32:
      return absl::StrCat(repeated ? r->GetRepeatedInt32(message, field, index)
                                   : r->GetInt32(message, field));
    case FieldDescriptor::CPPTYPE_INT64:
      return absl::StrCat(repeated ? r->GetRepeatedInt64(message, field, index)
                                   : r->GetInt64(message, field));
    case FieldDescriptor::CPPTYPE_DOUBLE:
      return absl::StrCat(repeated ? r->GetRepeatedDouble(message, field, index)
                                   : r->GetDouble(message, field));
    case FieldDescriptor::CPPTYPE_BOOL:
      return (repeated ? r->GetRepeatedBool(message, field, index) : r->GetBool(message, field))
                 ? "true"
                 : "false";
    case FieldDescriptor::CPPTYPE_ENUM:
      return (repeated ? r->GetRepeatedEnum(message, field, index) : r->GetEnum(message, field))
          ->name();
    default:
      ADD_FAILURE() << field->full_name()
                    << ": a query parameter of a type this test does not write";
      return "";
  }
}

}  // namespace

std::optional<RestRequest> RestFormOf(const MethodDescriptor* method, const Message& request) {
  if (!method->options().HasExtension(google::api::http)) return std::nullopt;
  const auto& rule = method->options().GetExtension(google::api::http);
  RestRequest rest;
  std::string path_template;
  switch (rule.pattern_case()) {
    case google::api::HttpRule::kGet:
      rest.verb = "GET", path_template = rule.get();
      break;
    case google::api::HttpRule::kPost:
      rest.verb = "POST", path_template = rule.post();
      break;
    case google::api::HttpRule::kDelete:
      rest.verb = "DELETE", path_template = rule.delete_();
      break;
    default:
      ADD_FAILURE() << method->full_name() << ": a verb this test does not send";
      return std::nullopt;
  }
  std::unique_ptr<Message> rest_of(request.New());
  rest_of->CopyFrom(request);
  const auto* reflection = rest_of->GetReflection();
  // {name=runs/*} → the request's name, "runs/<id>".
  const std::regex variable(R"(\{([^}=]+)(=[^}]*)?\})");
  std::size_t last = 0;
  for (std::sregex_iterator it(path_template.begin(), path_template.end(), variable), end;
       it != end; ++it) {
    rest.path += path_template.substr(last, static_cast<std::size_t>(it->position()) - last);
    const FieldDescriptor* field = rest_of->GetDescriptor()->FindFieldByName((*it)[1].str());
    EXPECT_NE(field, nullptr) << method->full_name() << ": path variable " << (*it)[1];
    if (field != nullptr) {
      rest.path += reflection->GetString(*rest_of, field);
      reflection->ClearField(rest_of.get(), field);
    }
    last = static_cast<std::size_t>(it->position() + it->length());
  }
  rest.path += path_template.substr(last);
  if (rule.body() == "*") {
    rest.body = api::ToJson(*rest_of).value_or("{}");
    return rest;
  }
  if (!rule.body().empty()) {
    const FieldDescriptor* field = rest_of->GetDescriptor()->FindFieldByName(rule.body());
    EXPECT_NE(field, nullptr) << method->full_name() << ": body " << rule.body();
    if (field == nullptr) return std::nullopt;
    rest.body = api::ToJson(reflection->GetMessage(*rest_of, field)).value_or("{}");
    reflection->ClearField(rest_of.get(), field);
  }
  std::vector<const FieldDescriptor*> set;
  reflection->ListFields(*rest_of, &set);
  std::string query;
  for (const FieldDescriptor* field : set) {
    const int count = field->is_repeated() ? reflection->FieldSize(*rest_of, field) : 1;
    for (int i = 0; i < count; ++i) {
      absl::StrAppend(&query, query.empty() ? "?" : "&", field->json_name(), "=",
                      httplib::detail::encode_query_param(QueryValue(*rest_of, field, i)));
    }
  }
  rest.path += query;
  return rest;
}

}  // namespace insdiag::testing
