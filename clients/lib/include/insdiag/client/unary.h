// One unary gRPC call as an absl::StatusOr, with a deadline: the CLI's verbs
// and the tests call the services this way.
//   auto analysis = client::CallUnary<v1::Analysis>(
//       [&](grpc::ClientContext* c, v1::Analysis* out) { return stub->GetAnalysis(c, request, out); });
#pragma once

#include <absl/status/statusor.h>
#include <grpcpp/grpcpp.h>

#include <chrono>

#include "insdiag/client/run_client.h"

namespace insdiag::client {

template <typename Response, typename Call>
absl::StatusOr<Response> CallUnary(Call&& call, std::chrono::seconds deadline = std::chrono::seconds(120)) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + deadline);
  Response response;
  const grpc::Status status = call(&context, &response);
  if (!status.ok()) return FromGrpc(status);
  return response;
}

}  // namespace insdiag::client
