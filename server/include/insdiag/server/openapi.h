// The REST face as an OpenAPI 3.0 document, generated from the services'
// descriptors and their google.api.http rules — the routes the gateway
// serves (rest_gateway.h), not a hand-written copy of them.
//
// Paths: a variable that spans segments ("/v1/{name=runs/*}") is written
// with one parameter per wildcard, named after the collection before it
// ("/v1/runs/{runsId}"); GET and DELETE take the request's other scalar
// fields as query parameters; a body rule names the request's schema. A
// server-streaming method answers newline-delimited JSON; one that returns
// google.api.HttpBody answers with a document of its own media type. Schemas follow
// protobuf's JSON mapping (int64 as strings, enums by name, Timestamp as
// RFC 3339).
#pragma once

#include <string>
#include <vector>

namespace google::protobuf {
class MethodDescriptor;
}  // namespace google::protobuf

namespace insdiag::server {

struct OpenApiOperation {
  std::string http_method;  // GET, POST, …
  std::string path;         // the http rule's template, "/v1/{name=runs/*}"
  std::string body;         // "", "*" or a field name
  const google::protobuf::MethodDescriptor* method = nullptr;
};

// A route the gateway serves beside the transcoded methods.
struct OpenApiExtraRoute {
  std::string http_method;
  std::string path;  // OpenAPI form, "/v1/runs/{runsId}:download"
  std::string summary;
  std::string content_type;  // of the 200 answer
  bool needs_token = true;
};

// The document, as JSON.
std::string OpenApiDocument(const std::vector<OpenApiOperation>& operations,
                            const std::vector<OpenApiExtraRoute>& extras);

// "/v1/{name=runs/*}:watch" → "/v1/runs/{runsId}:watch".
std::string OpenApiPath(const std::string& rule_path);

}  // namespace insdiag::server
