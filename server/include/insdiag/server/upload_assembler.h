// One bench-run upload stream checked as it arrives, without storage
// (RunService.UploadRun's contract, runs.proto): the metadata first, then
// sample chunks, then one sha256; every sample validated as it comes
// (benchrun::BenchRunValidator), the digest recomputed. RunService stores
// what Finish returns; the upload fuzzer drives it directly.
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <cstddef>
#include <memory>
#include <optional>
#include <string>

#include "insdiag/api/run_codec.h"
#include "insdiag/benchrun/bench_run_validation.h"
#include "insdiag/engine/bench_run.h"
#include "insdiag/kb/run_store.h"
#include "insdiag/v1/runs.pb.h"

namespace insdiag::server {

// A complete, valid upload: the run and what identifies it.
struct AssembledUpload {
  engine::BenchRun run;
  kb::UploadIdentity identity;
};

class UploadAssembler {
 public:
  // More than `max_samples` samples: RESOURCE_EXHAUSTED.
  explicit UploadAssembler(std::size_t max_samples);

  // INVALID_ARGUMENT for a message out of order or a refused sample.
  absl::Status Accept(const v1::UploadRunRequest& message);
  // INVALID_ARGUMENT when the stream ended before its sha256, or the run as a
  // whole is invalid.
  absl::StatusOr<AssembledUpload> Finish();

  // The run as received so far: the metadata and the samples accepted. Its
  // samples grow with each chunk; Finish moves it out.
  const engine::BenchRun& received() const { return run_; }

 private:
  absl::Status AcceptMetadata(const v1::RunMetadata& metadata);
  absl::Status AcceptSamples(const v1::SampleChunk& chunk);
  absl::Status AcceptDigest(const std::string& sha256);

  std::size_t max_samples_;
  enum class Stage { kMetadata, kSamples, kComplete } stage_ = Stage::kMetadata;
  v1::RunMetadata metadata_;
  engine::BenchRun run_;
  std::unique_ptr<benchrun::FieldPathLocator> locator_;
  std::optional<benchrun::BenchRunValidator> validator_;
  std::optional<api::SampleDigest> digest_;
  std::string sha256_;
};

}  // namespace insdiag::server
