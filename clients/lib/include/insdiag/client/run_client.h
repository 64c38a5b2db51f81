// Client side of insdiag.v1.RunService over gRPC, shared by the CLI and the
// tests.
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>
#include <grpcpp/grpcpp.h>

#include <chrono>
#include <memory>
#include <string>

#include "insdiag/api/run_codec.h"
#include "insdiag/engine/bench_run.h"
#include "insdiag/v1/runs.grpc.pb.h"

namespace insdiag::client {

inline constexpr char kDefaultServerAddress[] = "localhost:50051";

// $INSDIAG_SERVER, else localhost:50051.
std::string DefaultServerAddress();

// $INSDIAG_TOKEN, else "".
std::string DefaultToken();

// A channel to `address` (host:port) whose every call carries
// `authorization: Bearer <token>` (none when `token` is empty). With
// `ca_pem` (PEM certificates) the channel is TLS and the server's certificate
// must chain to them and name the address's host; without, plaintext.
std::shared_ptr<grpc::Channel> Connect(const std::string& address, const std::string& token,
                                       const std::string& ca_pem = "");

// A fresh random request id (UUID version 4).
std::string NewRequestId();

// The server's verdict as an absl::Status: code and message.
absl::Status FromGrpc(const grpc::Status& status);

struct UploadOptions {
  std::string request_id;  // empty: not idempotent
  std::size_t chunk_samples = api::kDefaultChunkSamples;
  std::chrono::seconds deadline{600};
};

// Streams `run` (metadata, sample chunks, sha256) and returns the stored run.
absl::StatusOr<v1::Run> UploadRun(v1::RunService::StubInterface& stub, const engine::BenchRun& run,
                                  const UploadOptions& options);

}  // namespace insdiag::client
