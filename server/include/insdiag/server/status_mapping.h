// Errors, in one place (AIP-193): absl::Status → gRPC status (canonical code
// 1:1, message, and a google.rpc.Status with details in the
// `grpc-status-details-bin` trailer) and gRPC status → HTTP status with the
// Google JSON error body
//   {"error": {"code": 400, "message": "...", "status": "INVALID_ARGUMENT",
//              "details": [{"@type": "type.googleapis.com/google.rpc.BadRequest", ...}]}}
//
// Details come from the absl::Status payloads: a bench-run refusal's
// InputLocation (benchrun::LocationOf) becomes a BadRequest field violation
// plus an ErrorInfo (reason INVALID_BENCH_RUN) carrying source, line and
// column; payloads attached with WithErrorInfo become ErrorInfo details.
#pragma once

#include <absl/status/status.h>
#include <grpcpp/support/status.h>

#include <map>
#include <string>

namespace insdiag::server {

// The ErrorInfo domain of insdiag's errors.
inline constexpr char kErrorDomain[] = "insdiag.v1";

// `status` with a google.rpc.ErrorInfo {reason, domain insdiag.v1, metadata}
// attached, for the mapping below to pass on.
absl::Status WithErrorInfo(absl::Status status, const std::string& reason,
                           const std::map<std::string, std::string>& metadata = {});

grpc::Status ToGrpcStatus(const absl::Status& status);

// Back to absl (for callers of the in-process channel); details are kept.
absl::Status FromGrpcStatus(const grpc::Status& status);

struct HttpError {
  int http_status = 500;
  std::string json_body;
};

// `method` names the RPC for an UNIMPLEMENTED status without a message.
HttpError ToHttpError(const grpc::Status& status, const std::string& method = "");

int HttpStatusOf(grpc::StatusCode code);

}  // namespace insdiag::server
