// The runs methods of insdiag.v1.RunService, once, independent of transport:
// requests in, responses or absl::Status out. The gRPC face adapts it
// (grpc_services.h); REST reaches it through gRPC (rest_gateway.h).
#pragma once

#include <absl/functional/function_ref.h>
#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <cstddef>

#include "insdiag/kb/run_store.h"
#include "insdiag/server/upload_assembler.h"
#include "insdiag/v1/runs.pb.h"

namespace insdiag::server {

class RunService {
 public:
  struct Options {
    // Larger uploads are refused with RESOURCE_EXHAUSTED (memory: ~100 bytes
    // a sample while the upload is checked).
    std::size_t max_upload_samples = 20'000'000;
  };

  RunService(kb::RunStore& store, Options options) : store_(store), options_(options) {}

  absl::StatusOr<v1::Run> GetRun(const v1::GetRunRequest& request);
  absl::StatusOr<v1::ListRunsResponse> ListRuns(const v1::ListRunsRequest& request);
  absl::Status DeleteRun(const v1::DeleteRunRequest& request);
  // Calls `send` per chunk until done or it returns false (client gone).
  absl::Status ReadRunSamples(const v1::ReadRunSamplesRequest& request,
                              absl::FunctionRef<bool(const v1::SampleChunk&)> send);

  // One upload stream: Accept each message in order, then Finish when the
  // stream has ended. Nothing is stored before Finish succeeds; an upload
  // dropped before (a broken stream) stores nothing.
  class Upload {
   public:
    // INVALID_ARGUMENT for a message out of order or a refused sample.
    absl::Status Accept(const v1::UploadRunRequest& message);
    // Checks completeness, validity and the digest, then stores the run in
    // one transaction.
    absl::StatusOr<v1::Run> Finish();
    // UploadAssembler::received.
    const engine::BenchRun& received() const { return assembler_.received(); }

   private:
    friend class RunService;
    explicit Upload(RunService& service) : service_(service), assembler_(service.options_.max_upload_samples) {}

    RunService& service_;
    UploadAssembler assembler_;
  };
  Upload StartUpload() { return Upload(*this); }

 private:
  kb::RunStore& store_;
  Options options_;
};

}  // namespace insdiag::server
