#include "insdiag/client/run_client.h"

#include <absl/strings/str_format.h>

#include <cstdlib>
#include <random>
#include <vector>

#include <grpcpp/support/client_interceptor.h>

#include "insdiag/benchrun/text_rules.h"

namespace insdiag::client {

std::string DefaultServerAddress() {
  const char* env = std::getenv("INSDIAG_SERVER");
  return env != nullptr && *env != '\0' ? env : kDefaultServerAddress;
}

std::string DefaultToken() {
  const char* env = std::getenv("INSDIAG_TOKEN");
  return env != nullptr ? env : "";
}

namespace {

// Adds the bearer token to every call's metadata. (gRPC's own call
// credentials are withheld from channels without TLS.)
class BearerToken final : public grpc::experimental::Interceptor {
 public:
  explicit BearerToken(std::string header) : header_(std::move(header)) {}
  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
    if (methods->QueryInterceptionHookPoint(grpc::experimental::InterceptionHookPoints::PRE_SEND_INITIAL_METADATA)) {
      methods->GetSendInitialMetadata()->insert({"authorization", header_});
    }
    methods->Proceed();
  }

 private:
  std::string header_;
};

class BearerTokenFactory final : public grpc::experimental::ClientInterceptorFactoryInterface {
 public:
  explicit BearerTokenFactory(std::string token) : header_("Bearer " + std::move(token)) {}
  grpc::experimental::Interceptor* CreateClientInterceptor(grpc::experimental::ClientRpcInfo*) override {
    return new BearerToken(header_);
  }

 private:
  std::string header_;
};

}  // namespace

std::shared_ptr<grpc::Channel> Connect(const std::string& address, const std::string& token,
                                       const std::string& ca_pem) {
  grpc::ChannelArguments arguments;
  // ReadRunSamples chunks of up to 50,000 samples are ~5 MB.
  arguments.SetMaxReceiveMessageSize(64 << 20);
  std::vector<std::unique_ptr<grpc::experimental::ClientInterceptorFactoryInterface>> interceptors;
  if (!token.empty()) interceptors.push_back(std::make_unique<BearerTokenFactory>(token));
  std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials();
  if (!ca_pem.empty()) {
    grpc::SslCredentialsOptions tls;
    tls.pem_root_certs = ca_pem;
    credentials = grpc::SslCredentials(tls);
  }
  return grpc::experimental::CreateCustomChannelWithInterceptors(address, credentials, arguments,
                                                                 std::move(interceptors));
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

namespace {

absl::Status CheckMetadataIsUtf8(const engine::BenchRunMetadata& metadata) {
  const auto check = [](const std::string& text, const std::string& field) {
    if (const auto bad = benchrun::FindInvalidUtf8(text)) {
      return absl::InvalidArgumentError(absl::StrFormat("upload: %s: byte 0x%02X at byte %d is not UTF-8 text", field,
                                                        static_cast<unsigned char>(text[*bad]), *bad + 1));
    }
    return absl::OkStatus();
  };
  if (absl::Status s = check(metadata.unit_serial, "metadata.unit_serial"); !s.ok()) return s;
  if (absl::Status s = check(metadata.unit_type, "metadata.unit_type"); !s.ok()) return s;
  for (std::size_t i = 0; i < metadata.extra.size(); ++i) {
    const std::string field = absl::StrFormat("metadata.extra[%d]", i);
    if (absl::Status s = check(metadata.extra[i].first, field); !s.ok()) return s;
    if (absl::Status s = check(metadata.extra[i].second, field); !s.ok()) return s;
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<v1::Run> UploadRun(v1::RunService::StubInterface& stub, const engine::BenchRun& run,
                                  const UploadOptions& options) {
  // Protobuf does not serialise a string that is not UTF-8 (it logs and
  // sends what the server cannot parse): such text is refused here, by field.
  if (absl::Status text = CheckMetadataIsUtf8(run.metadata); !text.ok()) return text;
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
