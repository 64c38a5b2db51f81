// Bench runs in and out of insdiag.v1 messages, and the upload digest.
//
// The server, the CLI and the tests convert between engine::BenchRun and the
// upload stream here, so that both ends agree on units (the proto carries the
// site in degrees, the engine in radians) and on what the sha256 covers.
#pragma once

#include <absl/functional/function_ref.h>
#include <absl/status/status.h>
#include <openssl/evp.h>

#include <cstddef>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "insdiag/api/sha256.h"  // Sha256, the digest of bytes
#include "insdiag/engine/bench_run.h"
#include "insdiag/v1/runs.pb.h"

namespace insdiag::api {

// Samples per SampleChunk message: 10,000 samples are ~1 MB on the wire,
// well under gRPC's 4 MB default message limit.
inline constexpr std::size_t kDefaultChunkSamples = 10'000;

v1::RunMetadata ToProto(const engine::BenchRunMetadata& metadata, bool has_temperature);
engine::BenchRunMetadata FromProto(const v1::RunMetadata& metadata);

v1::Sample ToProto(const engine::ImuSample& sample);
engine::ImuSample FromProto(const v1::Sample& sample);

// SHA-256 of samples as defined in runs.proto (UploadRunRequest.sha256):
// per sample the IEEE-754 binary64 little-endian bytes of t, gyro xyz,
// acc xyz, ref roll/pitch/yaw, and temp when the run has temperature.
class SampleDigest {
 public:
  explicit SampleDigest(bool has_temperature);
  SampleDigest(SampleDigest&&) noexcept = default;
  SampleDigest& operator=(SampleDigest&&) noexcept = default;
  ~SampleDigest() = default;

  void Add(const engine::ImuSample& sample);
  // Lower-case hex; the digest is finished after this call.
  std::string HexDigest();

 private:
  struct CtxDeleter {
    void operator()(EVP_MD_CTX* ctx) const { EVP_MD_CTX_free(ctx); }
  };
  bool has_temperature_;
  std::unique_ptr<EVP_MD_CTX, CtxDeleter> ctx_;
};

// The digest of a whole run.
std::string SampleSha256(const engine::BenchRun& run);

// The upload stream of `run`: metadata (with `request_id`), sample chunks of
// `chunk_samples`, then the digest. `send` returns false to stop early (a
// broken stream); the return value says whether every message was sent.
bool ForEachUploadRequest(const engine::BenchRun& run, const std::string& request_id,
                          std::size_t chunk_samples,
                          absl::FunctionRef<bool(const v1::UploadRunRequest&)> send);

}  // namespace insdiag::api
