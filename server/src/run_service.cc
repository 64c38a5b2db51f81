#include "insdiag/server/run_service.h"

#include <absl/strings/escaping.h>
#include <absl/strings/match.h>
#include <absl/strings/str_cat.h>
#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>
#include <openssl/evp.h>

#include <algorithm>
#include <array>

#include "insdiag/server/status_mapping.h"

namespace insdiag::server {
namespace {

constexpr char kRunPrefix[] = "runs/";
constexpr int kDefaultChunkSamples = 10'000;
constexpr int kMaxChunkSamples = 50'000;

absl::StatusOr<std::string> RunIdOf(const std::string& name) {
  if (!absl::StartsWith(name, kRunPrefix) || name.size() == sizeof kRunPrefix - 1 ||
      name.find('/', sizeof kRunPrefix - 1) != std::string::npos) {
    return absl::InvalidArgumentError(absl::StrCat("'", name, "' is not a run name (runs/{run})"));
  }
  return name.substr(sizeof kRunPrefix - 1);
}

v1::Run ToProto(const kb::StoredRun& stored) {
  v1::Run run;
  run.set_name(absl::StrCat(kRunPrefix, stored.id));
  *run.mutable_metadata() = api::ToProto(stored.metadata, stored.has_temperature);
  run.mutable_metadata()->set_request_id(stored.request_id);
  run.set_sample_count(stored.sample_count);
  run.set_nominal_interval_s(stored.nominal_interval_s);
  run.set_duration_s(stored.duration_s);
  run.set_first_t(stored.first_t_s);
  run.set_sha256(stored.sha256);
  run.mutable_create_time()->set_seconds(stored.create_time_unix_us / 1'000'000);
  run.mutable_create_time()->set_nanos(static_cast<int>(stored.create_time_unix_us % 1'000'000) * 1000);
  return run;
}

// What makes two uploads under one request id "the same": the metadata as
// sent (request id aside) and the samples' digest.
std::string UploadFingerprint(v1::RunMetadata metadata, const std::string& sample_sha256) {
  metadata.clear_request_id();
  std::string bytes;
  {
    google::protobuf::io::StringOutputStream stream(&bytes);
    google::protobuf::io::CodedOutputStream coded(&stream);
    coded.SetSerializationDeterministic(true);
    metadata.SerializeToCodedStream(&coded);
  }
  bytes += sample_sha256;
  std::array<unsigned char, EVP_MAX_MD_SIZE> digest{};
  unsigned int length = 0;
  EVP_Digest(bytes.data(), bytes.size(), digest.data(), &length, EVP_sha256(), nullptr);
  return std::string(reinterpret_cast<const char*>(digest.data()), length);
}

}  // namespace

absl::StatusOr<v1::Run> RunService::GetRun(const v1::GetRunRequest& request) {
  auto id = RunIdOf(request.name());
  if (!id.ok()) return id.status();
  auto stored = store_.Get(*id);
  if (!stored.ok()) return stored.status();
  return ToProto(*stored);
}

absl::StatusOr<v1::ListRunsResponse> RunService::ListRuns(const v1::ListRunsRequest& request) {
  if (request.page_size() < 0) return absl::InvalidArgumentError("page_size must not be negative");
  kb::RunQuery query;
  query.page_size = request.page_size();
  query.page_token = request.page_token();
  query.unit_serial = request.unit_serial();
  auto page = store_.List(query);
  if (!page.ok()) return page.status();
  v1::ListRunsResponse response;
  for (const auto& run : page->runs) *response.add_runs() = ToProto(run);
  response.set_next_page_token(page->next_page_token);
  return response;
}

absl::Status RunService::DeleteRun(const v1::DeleteRunRequest& request) {
  auto id = RunIdOf(request.name());
  if (!id.ok()) return id.status();
  return store_.Delete(*id);
}

absl::Status RunService::ReadRunSamples(const v1::ReadRunSamplesRequest& request,
                                        absl::FunctionRef<bool(const v1::SampleChunk&)> send) {
  auto id = RunIdOf(request.name());
  if (!id.ok()) return id.status();
  if (request.chunk_size() < 0 || request.chunk_size() > kMaxChunkSamples) {
    return absl::InvalidArgumentError(absl::StrCat("chunk_size must be within 0 … ", kMaxChunkSamples));
  }
  const int chunk_size = request.chunk_size() == 0 ? kDefaultChunkSamples : request.chunk_size();
  v1::SampleChunk chunk;
  return store_.ReadSamples(*id, static_cast<std::size_t>(chunk_size),
                            [&](std::span<const engine::ImuSample> samples) {
                              chunk.Clear();
                              chunk.mutable_samples()->Reserve(static_cast<int>(samples.size()));
                              for (const auto& sample : samples) *chunk.add_samples() = api::ToProto(sample);
                              return send(chunk);
                            });
}

RunService::Upload::Upload(RunService& service) : service_(service) {}

absl::Status RunService::Upload::Accept(const v1::UploadRunRequest& message) {
  switch (message.payload_case()) {
    case v1::UploadRunRequest::kMetadata:
      return AcceptMetadata(message.metadata());
    case v1::UploadRunRequest::kSamples:
      return AcceptSamples(message.samples());
    case v1::UploadRunRequest::kSha256:
      return AcceptDigest(message.sha256());
    default:
      return absl::InvalidArgumentError("an upload message carries none of metadata, samples, sha256");
  }
}

absl::Status RunService::Upload::AcceptMetadata(const v1::RunMetadata& metadata) {
  if (stage_ != Stage::kMetadata) {
    return absl::InvalidArgumentError("metadata must be the first message of an upload, and only the first");
  }
  metadata_ = metadata;
  run_.metadata = api::FromProto(metadata);
  run_.has_temperature = metadata.has_temperature();
  locator_ = std::make_unique<benchrun::FieldPathLocator>("upload");
  auto validator = benchrun::BenchRunValidator::Create(run_.metadata, run_.has_temperature, *locator_);
  if (!validator.ok()) return validator.status();
  validator_.emplace(std::move(*validator));
  digest_.emplace(run_.has_temperature);
  stage_ = Stage::kSamples;
  return absl::OkStatus();
}

absl::Status RunService::Upload::AcceptSamples(const v1::SampleChunk& chunk) {
  if (stage_ != Stage::kSamples) {
    return absl::InvalidArgumentError(stage_ == Stage::kMetadata
                                          ? "samples arrived before the upload's metadata"
                                          : "samples arrived after the upload's sha256");
  }
  if (run_.samples.size() + static_cast<std::size_t>(chunk.samples_size()) >
      service_.options_.max_upload_samples) {
    return absl::ResourceExhaustedError(
        absl::StrCat("an upload holds at most ", service_.options_.max_upload_samples, " samples"));
  }
  const std::size_t first = run_.samples.size();
  for (const auto& sample : chunk.samples()) run_.samples.push_back(api::FromProto(sample));
  const std::span<const engine::ImuSample> added(run_.samples.data() + first, run_.samples.size() - first);
  for (const auto& sample : added) digest_->Add(sample);
  return validator_->Add(added);
}

absl::Status RunService::Upload::AcceptDigest(const std::string& sha256) {
  if (stage_ != Stage::kSamples) {
    return absl::InvalidArgumentError(stage_ == Stage::kMetadata ? "sha256 arrived before the upload's metadata"
                                                                 : "an upload carries one sha256");
  }
  sha256_ = digest_->HexDigest();
  if (sha256 != sha256_) {
    return WithErrorInfo(
        absl::InvalidArgumentError(absl::StrCat("sha256 mismatch: the client sent ", sha256,
                                                " but the samples received hash to ", sha256_,
                                                "; the upload was corrupted or the client hashes differently "
                                                "(see UploadRunRequest.sha256)")),
        "SHA256_MISMATCH", {{"expected", sha256}, {"received", sha256_}});
  }
  stage_ = Stage::kComplete;
  return absl::OkStatus();
}

absl::StatusOr<v1::Run> RunService::Upload::Finish() {
  if (stage_ != Stage::kComplete) {
    return absl::InvalidArgumentError(
        absl::StrCat("the upload ended after ", run_.samples.size(),
                     " samples without its sha256 message; nothing was stored"));
  }
  if (auto status = validator_->Finish(); !status.ok()) return status;
  kb::UploadIdentity identity;
  identity.sha256 = sha256_;
  identity.request_id = metadata_.request_id();
  if (!identity.request_id.empty()) identity.request_fingerprint = absl::BytesToHexString(
      UploadFingerprint(metadata_, sha256_));
  auto stored = service_.store_.Create(run_, identity);
  if (!stored.ok()) {
    if (stored.status().code() == absl::StatusCode::kAlreadyExists) {
      return WithErrorInfo(stored.status(), "REQUEST_ID_REUSED", {{"request_id", identity.request_id}});
    }
    return stored.status();
  }
  return ToProto(*stored);
}

}  // namespace insdiag::server
