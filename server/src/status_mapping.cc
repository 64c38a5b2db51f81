#include "insdiag/server/status_mapping.h"

#include <absl/strings/cord.h>
#include <absl/strings/match.h>
#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>

#include <random>

#include "google/rpc/error_details.pb.h"
#include "google/rpc/status.pb.h"
#include "insdiag/api/json.h"
#include "insdiag/benchrun/bench_run_validation.h"
#include "insdiag/benchrun/text_rules.h"
#include "insdiag/kb/pg.h"
#include "insdiag/server/server_log.h"

namespace insdiag::server {
namespace {

constexpr char kGoogleRpcTypePrefix[] = "type.googleapis.com/google.rpc.";
constexpr char kErrorInfoTypeUrl[] = "type.googleapis.com/google.rpc.ErrorInfo";

// Canonical code names, as the JSON error body's `status` spells them.
const char* CodeName(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::OK: return "OK";
    case grpc::StatusCode::CANCELLED: return "CANCELLED";
    case grpc::StatusCode::UNKNOWN: return "UNKNOWN";
    case grpc::StatusCode::INVALID_ARGUMENT: return "INVALID_ARGUMENT";
    case grpc::StatusCode::DEADLINE_EXCEEDED: return "DEADLINE_EXCEEDED";
    case grpc::StatusCode::NOT_FOUND: return "NOT_FOUND";
    case grpc::StatusCode::ALREADY_EXISTS: return "ALREADY_EXISTS";
    case grpc::StatusCode::PERMISSION_DENIED: return "PERMISSION_DENIED";
    case grpc::StatusCode::RESOURCE_EXHAUSTED: return "RESOURCE_EXHAUSTED";
    case grpc::StatusCode::FAILED_PRECONDITION: return "FAILED_PRECONDITION";
    case grpc::StatusCode::ABORTED: return "ABORTED";
    case grpc::StatusCode::OUT_OF_RANGE: return "OUT_OF_RANGE";
    case grpc::StatusCode::UNIMPLEMENTED: return "UNIMPLEMENTED";
    case grpc::StatusCode::INTERNAL: return "INTERNAL";
    case grpc::StatusCode::UNAVAILABLE: return "UNAVAILABLE";
    case grpc::StatusCode::DATA_LOSS: return "DATA_LOSS";
    case grpc::StatusCode::UNAUTHENTICATED: return "UNAUTHENTICATED";
    default: return "UNKNOWN";
  }
}

// The codes that tell of the server's own trouble, not of the request: their
// messages may hold SQL, paths or values no client should see.
bool IsServersTrouble(absl::StatusCode code) {
  return code == absl::StatusCode::kInternal || code == absl::StatusCode::kUnknown ||
         code == absl::StatusCode::kDataLoss;
}

// A reference that finds an error's detail in the log: 8 hex digits.
std::string NewErrorReference() {
  thread_local std::mt19937 random(std::random_device{}());
  return absl::StrFormat("%08x", random());
}

google::rpc::Status RpcStatusOf(const absl::Status& status) {
  google::rpc::Status rpc;
  rpc.set_code(static_cast<int>(status.code()));
  rpc.set_message(std::string(status.message()));
  if (const auto where = benchrun::LocationOf(status)) {
    google::rpc::BadRequest bad_request;
    auto* violation = bad_request.add_field_violations();
    violation->set_field(where->line > 0 ? absl::StrCat(where->source, ":", where->line, ":", where->column,
                                                        where->field.empty() ? "" : " ", where->field)
                                         : where->field);
    violation->set_description(std::string(status.message()));
    rpc.add_details()->PackFrom(bad_request);
    google::rpc::ErrorInfo info;
    info.set_reason("INVALID_BENCH_RUN");
    info.set_domain(kErrorDomain);
    auto& metadata = *info.mutable_metadata();
    metadata["source"] = where->source;
    metadata["field"] = where->field;
    if (where->line > 0) {
      metadata["line"] = std::to_string(where->line);
      metadata["column"] = std::to_string(where->column);
    }
    rpc.add_details()->PackFrom(info);
  }
  // Payloads that already are google.rpc details travel as they are.
  status.ForEachPayload([&](absl::string_view type_url, const absl::Cord& payload) {
    if (!absl::StartsWith(type_url, kGoogleRpcTypePrefix)) return;
    auto* detail = rpc.add_details();
    detail->set_type_url(std::string(type_url));
    detail->set_value(std::string(payload));
  });
  return rpc;
}

}  // namespace

absl::Status WithErrorInfo(absl::Status status, const std::string& reason,
                           const std::map<std::string, std::string>& metadata) {
  google::rpc::ErrorInfo info;
  info.set_reason(reason);
  info.set_domain(kErrorDomain);
  for (const auto& [key, value] : metadata) (*info.mutable_metadata())[key] = value;
  status.SetPayload(kErrorInfoTypeUrl, absl::Cord(info.SerializeAsString()));
  return status;
}

grpc::Status ToGrpcStatus(const absl::Status& status) {
  if (status.ok()) return grpc::Status::OK;
  // absl and gRPC share the canonical code numbers.
  const auto code = static_cast<grpc::StatusCode>(status.code());
  if (IsServersTrouble(status.code())) {
    const std::string reference = NewErrorReference();
    Log(LogLevel::kError, absl::StrCat("error ", reference, " (", CodeName(code), "): ", status.message()));
    return grpc::Status(code, absl::StrCat("internal error ", reference,
                                           "; the server's log tells what happened under this reference"));
  }
  std::string message(status.message());
  if (status.GetPayload(kb::kSqlErrorPayload).has_value()) {
    // A refusal of the database's (a constraint): its words, not the statement.
    if (const std::size_t sql = message.rfind(" ["); sql != std::string::npos) message.resize(sql);
  }
  if (benchrun::FindInvalidUtf8(message).has_value()) message = benchrun::Utf8Printable(message);
  google::rpc::Status rpc = RpcStatusOf(status);
  rpc.set_message(message);
  return grpc::Status(code, message,
                      rpc.details_size() > 0 ? rpc.SerializeAsString() : std::string());
}

absl::Status FromGrpcStatus(const grpc::Status& status) {
  if (status.ok()) return absl::OkStatus();
  absl::Status out(static_cast<absl::StatusCode>(status.error_code()), status.error_message());
  google::rpc::Status rpc;
  if (!status.error_details().empty() && rpc.ParseFromString(status.error_details())) {
    for (const auto& detail : rpc.details()) out.SetPayload(detail.type_url(), absl::Cord(detail.value()));
  }
  return out;
}

int HttpStatusOf(grpc::StatusCode code) {
  // The mapping of google.rpc.Code's documentation.
  switch (code) {
    case grpc::StatusCode::OK: return 200;
    case grpc::StatusCode::CANCELLED: return 499;
    case grpc::StatusCode::INVALID_ARGUMENT: return 400;
    case grpc::StatusCode::FAILED_PRECONDITION: return 400;
    case grpc::StatusCode::OUT_OF_RANGE: return 400;
    case grpc::StatusCode::DEADLINE_EXCEEDED: return 504;
    case grpc::StatusCode::NOT_FOUND: return 404;
    case grpc::StatusCode::ALREADY_EXISTS: return 409;
    case grpc::StatusCode::ABORTED: return 409;
    case grpc::StatusCode::PERMISSION_DENIED: return 403;
    case grpc::StatusCode::UNAUTHENTICATED: return 401;
    case grpc::StatusCode::RESOURCE_EXHAUSTED: return 429;
    case grpc::StatusCode::UNIMPLEMENTED: return 501;
    case grpc::StatusCode::UNAVAILABLE: return 503;
    default: return 500;
  }
}

HttpError ToHttpError(const grpc::Status& status, const std::string& method) {
  std::string message = status.error_message();
  if (message.empty() && status.error_code() == grpc::StatusCode::UNIMPLEMENTED) {
    message = absl::StrCat(method.empty() ? "this method" : method, " is not implemented yet");
  }
  google::rpc::Status rpc;
  if (!status.error_details().empty()) rpc.ParseFromString(status.error_details());
  rpc.set_code(HttpStatusOf(status.error_code()));
  rpc.set_message(message);
  // The body is google.rpc.Status in JSON with the HTTP code in `code`, plus
  // the canonical name in `status` (a field google.rpc.Status lacks).
  auto json = api::ToJson(rpc);
  if (!json.ok()) {  // a detail of a type this binary cannot print: leave details out
    rpc.clear_details();
    json = api::ToJson(rpc);
  }
  std::string body = json.ok() ? *json : "{}";
  body.pop_back();  // the closing brace
  absl::StrAppend(&body, body.size() > 1 ? "," : "", "\"status\":\"", CodeName(status.error_code()), "\"}");
  return HttpError{HttpStatusOf(status.error_code()), absl::StrCat("{\"error\":", body, "}")};
}

}  // namespace insdiag::server
