#include "insdiag/server/rest_gateway.h"

#include <absl/strings/ascii.h>
#include <absl/strings/match.h>
#include <absl/strings/numbers.h>
#include <absl/strings/str_cat.h>
#include <absl/strings/str_split.h>
#include <absl/strings/strip.h>
#include <google/protobuf/descriptor.h>
#include <google/protobuf/dynamic_message.h>

#include <algorithm>

#include "google/api/annotations.pb.h"
#include "in_process_call.h"
#include "insdiag/api/json.h"
#include "insdiag/api/run_codec.h"
#include "insdiag/benchrun/bench_run_csv.h"
#include "insdiag/engine/status_macros.h"
#include "insdiag/server/access_guard.h"
#include "insdiag/server/openapi.h"
#include "insdiag/server/status_mapping.h"
#include "insdiag/v1/access.pb.h"
#include "insdiag/v1/runs.pb.h"
#include "request_edge.h"
#include "rest_request.h"

// Last: httplib.h pulls in <resolv.h>, whose `_res` macro breaks Eigen's headers.
#include <httplib.h>

namespace insdiag::server {
namespace {

using google::protobuf::FieldDescriptor;
using google::protobuf::Message;

constexpr char kJson[] = "application/json";
constexpr char kNdjson[] = "application/x-ndjson";
constexpr char kUploadMethod[] = "insdiag.v1.RunService.UploadRun";

void SendStatus(httplib::Response& response, const grpc::Status& status, const std::string& method = "") {
  const HttpError error = ToHttpError(status, method);
  response.status = error.http_status;
  // RFC 6750 §3: a 401 names the scheme the client should use.
  if (status.error_code() == grpc::StatusCode::UNAUTHENTICATED) {
    response.set_header("WWW-Authenticate", R"(Bearer realm="insdiag")");
  }
  response.set_content(error.json_body, kJson);
}

void SendStatus(httplib::Response& response, const absl::Status& status) {
  SendStatus(response, ToGrpcStatus(status));
}

// A google.api.HttpBody answer is the body itself, under its own media type
// (the transcoding rule for documents that are not JSON: the test report).
constexpr char kHttpBody[] = "google.api.HttpBody";

void SendHttpBody(httplib::Response& response, const Message& message) {
  const auto* type = message.GetDescriptor();
  const auto* reflection = message.GetReflection();
  response.status = 200;
  response.set_content(reflection->GetString(message, type->FindFieldByName("data")),
                       reflection->GetString(message, type->FindFieldByName("content_type")));
}

void SendJson(httplib::Response& response, const Message& message) {
  auto json = api::ToJson(message);
  if (!json.ok()) return SendStatus(response, json.status());
  response.status = 200;
  response.set_content(*json, kJson);
}

std::unique_ptr<Message> NewMessage(const google::protobuf::Descriptor* type) {
  return std::unique_ptr<Message>(
      google::protobuf::MessageFactory::generated_factory()->GetPrototype(type)->New());
}

std::string MediaType(const httplib::Request& request) {
  std::string type = request.get_header_value("Content-Type");
  type = type.substr(0, type.find(';'));
  type.erase(std::remove(type.begin(), type.end(), ' '), type.end());
  return absl::AsciiStrToLower(type);
}

// The gateway's own routes, beside the transcoded methods: what the document
// says of them, and what routes() lists.
struct OwnRoute {
  const char* http_method;
  const char* path_template;
  const char* summary;
  const char* content_type;
  bool needs_token;
};
constexpr char kDownloadTemplate[] = "/v1/{name=runs/*}:download";
constexpr char kMetricsPath[] = "/metrics";
constexpr OwnRoute kOwnRoutes[] = {
    {"GET", kDownloadTemplate, "the run as a bench-run CSV file", "text/csv", true},
    {"GET", "/healthz", "SERVING, or 503 while the database does not answer", "text/plain", false},
    {"GET", kMetricsPath, "the Prometheus text (docs/API.md, Metrics)", "text/plain", true},
    {"GET", "/v1/openapi.json", "this document", "application/json", true},
};

std::string Param(const httplib::Request& request, const char* json_name, const char* proto_name) {
  if (request.has_param(json_name)) return request.get_param_value(json_name);
  return request.get_param_value(proto_name);
}

}  // namespace

absl::StatusOr<std::unique_ptr<RestGateway>> RestGateway::Create(std::shared_ptr<grpc::Channel> channel,
                                                                 const std::vector<std::string>& services,
                                                                 std::string gateway_key) {
  std::unique_ptr<RestGateway> gateway(new RestGateway(std::move(channel), std::move(gateway_key)));
  const auto* pool = google::protobuf::DescriptorPool::generated_pool();
  std::vector<OpenApiOperation> operations;
  for (const auto& service_name : services) {
    const auto* service = pool->FindServiceByName(service_name);
    if (service == nullptr) return absl::InvalidArgumentError(absl::StrCat("unknown service ", service_name));
    for (int m = 0; m < service->method_count(); ++m) {
      const auto* method = service->method(m);
      if (!method->options().HasExtension(google::api::http)) continue;
      const google::api::HttpRule& rule = method->options().GetExtension(google::api::http);
      std::vector<const google::api::HttpRule*> rules = {&rule};
      for (const auto& extra : rule.additional_bindings()) rules.push_back(&extra);
      for (const auto* binding : rules) {
        std::string verb;
        std::string path;
        switch (binding->pattern_case()) {
          case google::api::HttpRule::kGet: verb = "GET", path = binding->get(); break;
          case google::api::HttpRule::kPut: verb = "PUT", path = binding->put(); break;
          case google::api::HttpRule::kPost: verb = "POST", path = binding->post(); break;
          case google::api::HttpRule::kDelete: verb = "DELETE", path = binding->delete_(); break;
          case google::api::HttpRule::kPatch: verb = "PATCH", path = binding->patch(); break;
          case google::api::HttpRule::kCustom: verb = binding->custom().kind(), path = binding->custom().path(); break;
          default: continue;
        }
        INSDIAG_ASSIGN_OR_RETURN(auto parsed, PathTemplate::Parse(path));
        gateway->routes_.push_back(
            Route{verb, std::move(parsed), binding->body(), method,
                  absl::StrCat("/", service->full_name(), "/", method->name())});
        operations.push_back(OpenApiOperation{verb, path, binding->body(), method});
      }
    }
  }
  std::vector<OpenApiExtraRoute> extras;
  for (const OwnRoute& own : kOwnRoutes) {
    extras.push_back({own.http_method, OpenApiPath(own.path_template), own.summary,
                      own.content_type, own.needs_token});
  }
  gateway->openapi_json_ = OpenApiDocument(operations, extras);
  // "runs/x:download" must reach the :download route, not GetRun.
  std::stable_sort(gateway->routes_.begin(), gateway->routes_.end(),
                   [](const Route& a, const Route& b) { return a.path.has_verb() && !b.path.has_verb(); });
  return gateway;
}

std::vector<RestRoute> RestGateway::routes() const {
  std::vector<RestRoute> served;
  for (const Route& route : routes_) {
    served.push_back({route.http_method, route.path.text(), route.method->full_name()});
  }
  for (const OwnRoute& own : kOwnRoutes) {
    if (own.path_template == std::string_view(kMetricsPath) && !render_metrics_) continue;
    served.push_back({own.http_method, own.path_template, ""});
  }
  return served;
}

CallMetadata RestGateway::MetadataOf(const httplib::Request& request) const {
  CallMetadata metadata;
  if (request.has_header("Authorization")) metadata.emplace_back("authorization", request.get_header_value("Authorization"));
  const bool v6 = absl::StrContains(request.remote_addr, ':');
  metadata.emplace_back(kPeerMetadata, absl::StrCat(v6 ? "ipv6:[" : "ipv4:", request.remote_addr, v6 ? "]:" : ":",
                                                    request.remote_port));
  metadata.emplace_back(kGatewayKeyMetadata, gateway_key_);
  return metadata;
}

void RestGateway::Register(httplib::Server& http) {
  const auto handler = [this](const httplib::Request& request, httplib::Response& response) {
    Handle(request, response);
  };
  http.Get(".*", handler);
  http.Post(".*", handler);
  http.Put(".*", handler);
  http.Patch(".*", handler);
  http.Delete(".*", handler);
}

void RestGateway::Handle(const httplib::Request& request, httplib::Response& response) {
  // Before anything reaches a call's metadata, a request field or a log.
  if (absl::Status edge = CheckRequestEdge(request); !edge.ok()) return SendStatus(response, edge);
  if (request.method == "GET" && request.path == "/healthz") return Health(response);
  if (request.method == "GET" && request.path == kMetricsPath && render_metrics_)
    return Metrics(request, response);
  if (request.method == "GET" && request.path == "/v1/openapi.json") {
    if (!AdmitAnyRole(request, response)) return;
    response.status = 200;
    return response.set_content(openapi_json_, "application/json");
  }
  static const auto download = *PathTemplate::Parse(kDownloadTemplate);
  if (request.method == "GET") {
    if (auto bindings = download.Match(request.path)) return Download(bindings->at("name"), request, response);
  }
  for (const auto& route : routes_) {
    if (route.http_method != request.method) continue;
    if (auto bindings = route.path.Match(request.path)) return Dispatch(route, *bindings, request, response);
  }
  SendStatus(response, absl::NotFoundError(absl::StrCat("no method answers ", request.method, " ", request.path)));
}

void RestGateway::Dispatch(const Route& route, const std::map<std::string, std::string>& bindings,
                           const httplib::Request& request, httplib::Response& response) {
  if (route.method->full_name() == kUploadMethod) return Upload(route, request, response);
  if (route.method->client_streaming()) {
    return SendStatus(response, absl::UnimplementedError(absl::StrCat(
                                    route.method->full_name(), " streams requests; it has no REST form")));
  }
  auto message = NewMessage(route.method->input_type());
  if (auto status = BuildRequest(route.body, bindings, request, *message); !status.ok()) {
    return SendStatus(response, status);
  }
  auto call = std::make_shared<InProcessCall>(stub_, route.grpc_path, MetadataOf(request));
  call->Write(message->SerializeAsString());
  call->WritesDone();
  std::string bytes;
  if (!call->Read(&bytes)) return SendStatus(response, call->Finish(), route.method->full_name());
  auto first = NewMessage(route.method->output_type());
  first->ParseFromString(bytes);
  if (!route.method->server_streaming()) {
    const grpc::Status status = call->Finish();
    if (!status.ok()) return SendStatus(response, status, route.method->full_name());
    if (route.method->output_type()->full_name() == kHttpBody) return SendHttpBody(response, *first);
    return SendJson(response, *first);
  }
  // Newline-delimited JSON, streamed as the responses arrive. An error after
  // the first response can only be told in the body: a last line {"error":…}.
  response.status = 200;
  response.set_chunked_content_provider(
      kNdjson, [call, first = std::shared_ptr<Message>(std::move(first)), method = route.method](
                   std::size_t, httplib::DataSink& sink) mutable {
        auto write = [&](const Message& chunk) {
          auto json = api::ToJson(chunk);
          const std::string line = (json.ok() ? *json : "{}") + "\n";
          return sink.write(line.data(), line.size());
        };
        bool open = write(*first);
        std::string next_bytes;
        auto next = NewMessage(method->output_type());
        while (open && call->Read(&next_bytes)) {
          next->ParseFromString(next_bytes);
          open = write(*next);
        }
        if (!open) call->Cancel();
        const grpc::Status status = call->Finish();
        if (open && !status.ok()) {
          const std::string line = ToHttpError(status, method->full_name()).json_body + "\n";
          sink.write(line.data(), line.size());
        }
        sink.done();
        return true;
      });
}

void RestGateway::Upload(const Route& route, const httplib::Request& request, httplib::Response& response) {
  const std::string type = MediaType(request);
  InProcessCall call(stub_, route.grpc_path, MetadataOf(request));
  if (type == "text/csv") {
    const std::string source = request.has_param("filename") ? request.get_param_value("filename") : "body";
    auto run = benchrun::ParseBenchRun(request.body, source);
    if (!run.ok()) return SendStatus(response, run.status());
    api::ForEachUploadRequest(*run, Param(request, "requestId", "request_id"), api::kDefaultChunkSamples,
                              [&](const v1::UploadRunRequest& message) {
                                return call.Write(message.SerializeAsString());
                              });
  } else if (type == kNdjson || type == kJson) {
    v1::UploadRunRequest message;
    int line_number = 0;
    for (absl::string_view line : absl::StrSplit(request.body, '\n')) {
      ++line_number;
      if (absl::StripAsciiWhitespace(line).empty()) continue;
      if (auto status = api::FromJson(std::string(line), &message); !status.ok()) {
        return SendStatus(response, absl::InvalidArgumentError(absl::StrCat("body line ", line_number, ": ",
                                                                            status.message())));
      }
      if (!call.Write(message.SerializeAsString())) break;
    }
  } else {
    return SendStatus(response, absl::InvalidArgumentError(absl::StrCat(
                                    "POST /v1/runs:upload takes text/csv (a bench-run file) or ", kNdjson,
                                    " (UploadRunRequest messages), not '", type, "'")));
  }
  call.WritesDone();
  std::string bytes;
  v1::Run run;
  if (call.Read(&bytes)) run.ParseFromString(bytes);
  const grpc::Status status = call.Finish();
  if (!status.ok()) return SendStatus(response, status);
  SendJson(response, run);
}

bool RestGateway::AdmitAnyRole(const httplib::Request& request, httplib::Response& response) {
  InProcessCall call(stub_, "/insdiag.v1.AccessService/GetCaller", MetadataOf(request));
  call.Write(v1::GetCallerRequest().SerializeAsString());
  call.WritesDone();
  std::string bytes;
  call.Read(&bytes);
  if (const auto status = call.Finish(); !status.ok()) {
    SendStatus(response, status);
    return false;
  }
  return true;
}

void RestGateway::Metrics(const httplib::Request& request, httplib::Response& response) {
  if (!AdmitAnyRole(request, response)) return;
  response.status = 200;
  response.set_content(render_metrics_(), "text/plain; version=0.0.4; charset=utf-8");
}

void RestGateway::Download(const std::string& run_name, const httplib::Request& request, httplib::Response& response) {
  const CallMetadata metadata = MetadataOf(request);
  engine::BenchRun run;
  {
    v1::GetRunRequest get;
    get.set_name(run_name);
    InProcessCall call(stub_, "/insdiag.v1.RunService/GetRun", metadata);
    call.Write(get.SerializeAsString());
    call.WritesDone();
    std::string bytes;
    v1::Run stored;
    if (call.Read(&bytes)) stored.ParseFromString(bytes);
    if (const auto status = call.Finish(); !status.ok()) return SendStatus(response, status);
    run.metadata = api::FromProto(stored.metadata());
    run.has_temperature = stored.metadata().has_temperature();
    run.samples.reserve(static_cast<std::size_t>(stored.sample_count()));
  }
  v1::ReadRunSamplesRequest read;
  read.set_name(run_name);
  InProcessCall call(stub_, "/insdiag.v1.RunService/ReadRunSamples", metadata);
  call.Write(read.SerializeAsString());
  call.WritesDone();
  std::string bytes;
  v1::SampleChunk chunk;
  while (call.Read(&bytes)) {
    chunk.ParseFromString(bytes);
    for (const auto& sample : chunk.samples()) run.samples.push_back(api::FromProto(sample));
  }
  if (const auto status = call.Finish(); !status.ok()) return SendStatus(response, status);
  response.status = 200;
  response.set_content(benchrun::FormatBenchRun(run), "text/csv");
}

void RestGateway::Health(httplib::Response& response) {
  // grpc.health.v1.Health/Check with an empty request (the whole server).
  // Its response is HealthCheckResponse{status = 1 (SERVING)}, on the wire
  // the two bytes 08 01; Debian ships no C++ code generated from health.proto.
  InProcessCall call(stub_, "/grpc.health.v1.Health/Check", {});
  call.Write("");
  call.WritesDone();
  std::string bytes;
  const bool answered = call.Read(&bytes);
  const grpc::Status status = call.Finish();
  if (!status.ok()) return SendStatus(response, status);
  const bool serving = answered && bytes == std::string("\x08\x01", 2);
  response.status = serving ? 200 : 503;
  response.set_content(serving ? R"({"status":"SERVING"})" : R"({"status":"NOT_SERVING"})", kJson);
}

}  // namespace insdiag::server
