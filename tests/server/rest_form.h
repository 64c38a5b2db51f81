// A request message in the form the REST face takes it (rest_gateway.h):
// the method's google.api.http verb and path, its variables filled from the
// request, the body the rule names as JSON, every other set scalar field a
// query parameter by its JSON name.
#pragma once

#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>

#include <optional>
#include <string>

namespace insdiag::testing {

struct RestRequest {
  std::string verb;
  std::string path;  // with the query
  std::string body;
  std::string content_type = "application/json";
};

// nullopt for a method without an http rule (a test failure is added for a
// rule this cannot write).
std::optional<RestRequest> RestFormOf(const google::protobuf::MethodDescriptor* method,
                                      const google::protobuf::Message& request);

}  // namespace insdiag::testing
