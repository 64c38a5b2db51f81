// A REST request turned into a method's request message (rest_gateway.h):
// the JSON body under the http rule's `body`, then query parameters, then
// path variables, each refused with INVALID_ARGUMENT naming the parameter.
#pragma once

#include <absl/status/status.h>
#include <google/protobuf/message.h>

#include <map>
#include <string>

namespace httplib {
struct Request;
}  // namespace httplib

namespace insdiag::server {

// Sets the scalar at dotted `path` (proto or JSON names) from its text, as
// path variables and query parameters carry it; repeated fields get an
// element added.
absl::Status SetFieldFromText(google::protobuf::Message& message, const std::string& path, const std::string& text);

// The request message of a non-streaming-request method from the HTTP
// request; `body_rule` is the http rule's body ("", "*" or a field name).
absl::Status BuildRequest(const std::string& body_rule, const std::map<std::string, std::string>& bindings,
                          const httplib::Request& http, google::protobuf::Message& request);

}  // namespace insdiag::server
