// Who may call what, in one place for every method of every service: the
// bearer token from the call's metadata, the method's access rule from its
// proto option (proto/insdiag/v1/access.proto), and an audit event for every
// call of a writing method, admitted or refused.
//
// REST reaches the services through the in-process channel
// (rest_gateway.h), carrying the HTTP Authorization header as the
// `authorization` metadata and the HTTP client's address as `kPeerMetadata`.
// That address is believed only beside this guard's gateway key
// (`kGatewayKeyMetadata`), a random value that never leaves the process: a
// gRPC client cannot pass itself off as someone else.
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>
#include <grpcpp/grpcpp.h>

#include <string>
#include <absl/strings/string_view.h>
#include <vector>

#include "insdiag/kb/access_store.h"
#include "insdiag/server/status_mapping.h"
#include "insdiag/v1/access.pb.h"

namespace google::protobuf {
class Message;
class MethodDescriptor;
}  // namespace google::protobuf

namespace insdiag::server {

// The REST client's address, set by the gateway on its in-process calls.
inline constexpr char kPeerMetadata[] = "x-insdiag-peer";
inline constexpr char kGatewayKeyMetadata[] = "x-insdiag-gateway-key";

class AccessGuard {
 public:
  explicit AccessGuard(kb::AccessStore& store);

  // What the REST gateway sends beside kPeerMetadata.
  const std::string& gateway_key() const { return gateway_key_; }

  // INTERNAL naming the first method of `services` (full names) without an
  // access rule: the server does not start with an unguarded method.
  static absl::Status CheckEveryMethodHasARule(const std::vector<std::string>& services);

  // The caller, admitted to `method` ("insdiag.v1.RunService.DeleteRun"):
  // UNAUTHENTICATED without a valid bearer token, PERMISSION_DENIED for a
  // role below the method's. A refused call of a writing method is audited.
  absl::StatusOr<kb::Caller> Admit(const grpc::ServerContext& context, absl::string_view method);

  // Records the outcome of an admitted call when the method writes. The
  // resource is the request's `name`, else the response's (or its first
  // message field's) `name`, else the request's `parent`.
  void Audit(const grpc::ServerContext& context, absl::string_view method, const kb::Caller& caller,
             const google::protobuf::Message* request, const google::protobuf::Message* response,
             const absl::Status& outcome);

  // A unary method: admit, run `call(caller)` (an absl::StatusOr<Response>),
  // audit, answer.
  template <typename Response, typename Call>
  grpc::Status Unary(grpc::ServerContext& context, absl::string_view method, const google::protobuf::Message& request,
                     Response* response, Call&& call) {
    auto caller = Admit(context, method);
    if (!caller.ok()) return ToGrpcStatus(caller.status());
    absl::StatusOr<Response> result = call(*caller);
    if (result.ok()) *response = std::move(*result);
    Audit(context, method, *caller, &request, result.ok() ? response : nullptr, result.status());
    return result.ok() ? grpc::Status::OK : ToGrpcStatus(result.status());
  }

 private:
  const v1::AccessRule* RuleOf(absl::string_view method) const;
  // The caller of an `authorization` value "Bearer <secret>".
  absl::StatusOr<kb::Caller> Authenticate(absl::string_view authorization);
  std::string PeerOf(const grpc::ServerContext& context) const;

  kb::AccessStore& store_;
  std::string gateway_key_;
};

}  // namespace insdiag::server
