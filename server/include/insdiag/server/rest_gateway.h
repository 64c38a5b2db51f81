// The REST/JSON face: the services' methods at their google.api.http paths,
// with protobuf's JSON mapping, built at start-up from the service
// descriptors. A request is turned into the method's request message (path
// variables, query parameters and the JSON body), sent through the gRPC
// server's in-process channel, and the response printed as JSON: one
// implementation of every method, two transports, one status mapping.
//
// Beyond the transcoded methods:
//   POST /v1/runs:upload           text/csv body (a bench-run file; optional
//                                  ?requestId=) or application/x-ndjson
//                                  (one UploadRunRequest per line)
//   GET  /v1/runs/{run}:download   the run as a bench-run CSV file
//   GET  /healthz                  the gRPC health service's verdict
//   GET  /metrics                  the Prometheus text (metrics.h), to any
//                                  valid token (AccessService.GetCaller's rule)
//   GET  /v1/openapi.json          this face as an OpenAPI document
//                                  (openapi.h), to any valid token
// Server-streaming methods answer with newline-delimited JSON; a method that
// returns google.api.HttpBody answers with its data under its content type
// (GET /v1/analyses/{analysis}:testReport: HTML or PDF). Every call
// carries the Authorization header and the client's address to the services'
// access guard (access_guard.h); only /healthz and the page need none.
#pragma once

#include <absl/status/statusor.h>
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "insdiag/server/path_template.h"
#include "insdiag/server/rest_route.h"

namespace google::protobuf {
class MethodDescriptor;
}  // namespace google::protobuf

namespace httplib {
class Server;
struct Request;
struct Response;
}  // namespace httplib

namespace insdiag::server {

class RestGateway {
 public:
  // `services`: full names, e.g. "insdiag.v1.RunService". INVALID_ARGUMENT
  // for an unknown service or a malformed http rule.
  // `gateway_key`: what the access guard believes the client's address
  // beside (access_guard.h).
  static absl::StatusOr<std::unique_ptr<RestGateway>> Create(std::shared_ptr<grpc::Channel> channel,
                                                             const std::vector<std::string>& services,
                                                             std::string gateway_key);

  // Installs the handlers; the gateway must outlive `http`'s serving.
  void Register(httplib::Server& http);

  // Answers one request, as every route registered does: the edge checks
  // (request_edge.h), then the route. Public for the gateway's fuzzer.
  void Handle(const httplib::Request& request, httplib::Response& response);

  // Every route served: the methods' http rules in matching order, then the
  // gateway's own (/metrics only once ServeMetrics was called).
  std::vector<RestRoute> routes() const;

  // What GET /metrics answers; unset, 404.
  void ServeMetrics(std::function<std::string()> render) { render_metrics_ = std::move(render); }

 private:
  struct Route {
    std::string http_method;
    PathTemplate path;
    std::string body;  // "", "*" or a field name
    const google::protobuf::MethodDescriptor* method;
    std::string grpc_path;  // "/insdiag.v1.RunService/GetRun"
  };

  RestGateway(std::shared_ptr<grpc::Channel> channel, std::string gateway_key)
      : stub_(std::move(channel)), gateway_key_(std::move(gateway_key)) {}
  // The caller's credentials and address, for the services' access guard.
  std::vector<std::pair<std::string, std::string>> MetadataOf(const httplib::Request& request) const;
  void Dispatch(const Route& route, const std::map<std::string, std::string>& bindings,
                const httplib::Request& request, httplib::Response& response);
  void Upload(const Route& route, const httplib::Request& request, httplib::Response& response);
  void Download(const std::string& run_name, const httplib::Request& request, httplib::Response& response);
  void Metrics(const httplib::Request& request, httplib::Response& response);
  // Whether the request's token is valid (AccessService.GetCaller admits
  // it); when not, the refusal is answered.
  bool AdmitAnyRole(const httplib::Request& request, httplib::Response& response);
  void Health(httplib::Response& response);

  grpc::GenericStub stub_;
  std::string gateway_key_;
  std::function<std::string()> render_metrics_;
  std::string openapi_json_;
  std::vector<Route> routes_;  // custom-verb routes first
};

}  // namespace insdiag::server
