#include "insdiag/server/upload_assembler.h"

#include <absl/strings/escaping.h>
#include <absl/strings/str_cat.h>
#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>

#include "insdiag/engine/status_macros.h"
#include "insdiag/server/status_mapping.h"

namespace insdiag::server {
namespace {

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
  return api::Sha256(bytes);
}

}  // namespace

UploadAssembler::UploadAssembler(std::size_t max_samples) : max_samples_(max_samples) {}

absl::Status UploadAssembler::Accept(const v1::UploadRunRequest& message) {
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

absl::Status UploadAssembler::AcceptMetadata(const v1::RunMetadata& metadata) {
  if (stage_ != Stage::kMetadata) {
    return absl::InvalidArgumentError("metadata must be the first message of an upload, and only the first");
  }
  metadata_ = metadata;
  run_.metadata = api::FromProto(metadata);
  run_.has_temperature = metadata.has_temperature();
  locator_ = std::make_unique<benchrun::FieldPathLocator>("upload");
  INSDIAG_ASSIGN_OR_RETURN(auto validator, benchrun::BenchRunValidator::Create(
                                               run_.metadata, run_.has_temperature, *locator_));
  validator_.emplace(std::move(validator));
  digest_.emplace(run_.has_temperature);
  stage_ = Stage::kSamples;
  return absl::OkStatus();
}

absl::Status UploadAssembler::AcceptSamples(const v1::SampleChunk& chunk) {
  if (stage_ != Stage::kSamples) {
    return absl::InvalidArgumentError(stage_ == Stage::kMetadata
                                          ? "samples arrived before the upload's metadata"
                                          : "samples arrived after the upload's sha256");
  }
  if (run_.samples.size() + static_cast<std::size_t>(chunk.samples_size()) >
      max_samples_) {
    return absl::ResourceExhaustedError(
        absl::StrCat("an upload holds at most ", max_samples_, " samples"));
  }
  const std::size_t first = run_.samples.size();
  for (const auto& sample : chunk.samples()) run_.samples.push_back(api::FromProto(sample));
  const std::span<const engine::ImuSample> added(run_.samples.data() + first, run_.samples.size() - first);
  for (const auto& sample : added) digest_->Add(sample);
  return validator_->Add(added);
}

absl::Status UploadAssembler::AcceptDigest(const std::string& sha256) {
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

absl::StatusOr<AssembledUpload> UploadAssembler::Finish() {
  if (stage_ != Stage::kComplete) {
    return absl::InvalidArgumentError(
        absl::StrCat("the upload ended after ", run_.samples.size(),
                     " samples without its sha256 message, or a message of it did not parse (text fields "
                     "must be UTF-8); nothing was stored"));
  }
  INSDIAG_RETURN_IF_ERROR(validator_->Finish());
  AssembledUpload done;
  done.identity.sha256 = sha256_;
  done.identity.request_id = metadata_.request_id();
  if (!done.identity.request_id.empty()) {
    done.identity.request_fingerprint = absl::BytesToHexString(UploadFingerprint(metadata_, sha256_));
  }
  done.run = std::move(run_);
  return done;
}

}  // namespace insdiag::server
