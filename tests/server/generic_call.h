// Any method of any service called through a real gRPC channel by its path,
// with requests as serialized messages: a bidirectional generic call fits
// unary and streaming methods alike.
#pragma once

#include <grpcpp/generic/generic_stub.h>

#include <chrono>
#include <string>
#include <vector>

namespace insdiag::testing {

struct GenericAnswer {
  grpc::Status status;
  std::vector<std::string> responses;  // serialized, in the order received
};

// Sends `requests` in order to `path` ("/insdiag.v1.RunService/GetRun"),
// closes the stream, and reads every response until the status.
GenericAnswer CallGeneric(grpc::GenericStub& stub, const std::string& path,
                          const std::vector<std::string>& requests,
                          std::chrono::seconds deadline = std::chrono::seconds(60));

}  // namespace insdiag::testing
