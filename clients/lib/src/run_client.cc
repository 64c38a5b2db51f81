#include "insdiag/client/run_client.h"

#include <absl/strings/str_format.h>

#include <cstdlib>
#include <random>

namespace insdiag::client {

std::string DefaultServerAddress() {
  const char* env = std::getenv("INSDIAG_SERVER");
  return env != nullptr && *env != '\0' ? env : kDefaultServerAddress;
}

std::shared_ptr<grpc::Channel> Connect(const std::string& address) {
  grpc::ChannelArguments arguments;
  // ReadRunSamples chunks of up to 50,000 samples are ~5 MB.
  arguments.SetMaxReceiveMessageSize(64 << 20);
  return grpc::CreateCustomChannel(address, grpc::InsecureChannelCredentials(), arguments);
}

std::string NewRequestId() {
  std::random_device entropy;
  std::mt19937_64 generator((static_cast<std::uint64_t>(entropy()) << 32) ^ entropy());
  std::uint64_t high = generator();
  std::uint64_t low = generator();
  high = (high & ~0xf000ULL) | 0x4000ULL;                          // version 4
  low = (low & ~(0xc000ULL << 48)) | (0x8000ULL << 48);           // variant 10
  return absl::StrFormat("%08x-%04x-%04x-%04x-%012x", high >> 32, (high >> 16) & 0xffff, high & 0xffff,
                         low >> 48, low & 0xffffffffffffULL);
}

absl::Status FromGrpc(const grpc::Status& status) {
  if (status.ok()) return absl::OkStatus();
  return absl::Status(static_cast<absl::StatusCode>(status.error_code()), status.error_message());
}

absl::StatusOr<v1::Run> UploadRun(v1::RunService::StubInterface& stub, const engine::BenchRun& run,
                                  const UploadOptions& options) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + options.deadline);
  v1::Run stored;
  auto stream = stub.UploadRun(&context, &stored);
  // A failed Write means the server has already answered (a refusal);
  // Finish() below says why.
  if (api::ForEachUploadRequest(run, options.request_id, options.chunk_samples,
                                [&](const v1::UploadRunRequest& request) { return stream->Write(request); })) {
    stream->WritesDone();
  }
  if (auto status = FromGrpc(stream->Finish()); !status.ok()) return status;
  return stored;
}

}  // namespace insdiag::client
