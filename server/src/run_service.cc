#include "insdiag/server/run_service.h"

#include <absl/strings/str_cat.h>
#include <google/protobuf/util/time_util.h>

#include <algorithm>
#include <array>

#include "insdiag/api/resource_names.h"
#include "insdiag/engine/status_macros.h"
#include "insdiag/server/status_mapping.h"

namespace insdiag::server {
namespace {

constexpr int kDefaultChunkSamples = 10'000;
constexpr int kMaxChunkSamples = 50'000;

v1::Run ToProto(const kb::StoredRun& stored) {
  v1::Run run;
  run.set_name(api::ResourceName(api::kRuns, stored.id));
  *run.mutable_metadata() = api::ToProto(stored.metadata, stored.has_temperature);
  run.mutable_metadata()->set_request_id(stored.request_id);
  run.set_sample_count(stored.sample_count);
  run.set_nominal_interval_s(stored.nominal_interval_s);
  run.set_duration_s(stored.duration_s);
  run.set_first_t(stored.first_t_s);
  run.set_sha256(stored.sha256);
  *run.mutable_create_time() = google::protobuf::util::TimeUtil::MicrosecondsToTimestamp(stored.create_time_unix_us);
  return run;
}

}  // namespace

absl::StatusOr<v1::Run> RunService::GetRun(const v1::GetRunRequest& request) {
  INSDIAG_ASSIGN_OR_RETURN(auto id, api::ResourceId(request.name(), api::kRuns));
  INSDIAG_ASSIGN_OR_RETURN(auto stored, store_.Get(id));
  return ToProto(stored);
}

absl::StatusOr<v1::ListRunsResponse> RunService::ListRuns(const v1::ListRunsRequest& request) {
  if (request.page_size() < 0) return absl::InvalidArgumentError("page_size must not be negative");
  kb::RunQuery query;
  query.page_size = request.page_size();
  query.page_token = request.page_token();
  query.unit_serial = request.unit_serial();
  // Summaries: a run's free metadata (up to 1 MiB each) is GetRun's, so that
  // no page of runs outgrows a message whatever the runs hold.
  query.with_extra_metadata = false;
  INSDIAG_ASSIGN_OR_RETURN(auto page, store_.List(query));
  v1::ListRunsResponse response;
  for (const auto& run : page.runs) *response.add_runs() = ToProto(run);
  response.set_next_page_token(page.next_page_token);
  return response;
}

absl::Status RunService::DeleteRun(const v1::DeleteRunRequest& request) {
  INSDIAG_ASSIGN_OR_RETURN(auto id, api::ResourceId(request.name(), api::kRuns));
  return store_.Delete(id);
}

absl::Status RunService::ReadRunSamples(const v1::ReadRunSamplesRequest& request,
                                        absl::FunctionRef<bool(const v1::SampleChunk&)> send) {
  INSDIAG_ASSIGN_OR_RETURN(auto id, api::ResourceId(request.name(), api::kRuns));
  if (request.chunk_size() < 0 || request.chunk_size() > kMaxChunkSamples) {
    return absl::InvalidArgumentError(absl::StrCat("chunk_size must be within 0 … ", kMaxChunkSamples));
  }
  const int chunk_size = request.chunk_size() == 0 ? kDefaultChunkSamples : request.chunk_size();
  v1::SampleChunk chunk;
  return store_.ReadSamples(id, static_cast<std::size_t>(chunk_size),
                            [&](std::span<const engine::ImuSample> samples) {
                              chunk.Clear();
                              chunk.mutable_samples()->Reserve(static_cast<int>(samples.size()));
                              for (const auto& sample : samples)
                                *chunk.add_samples() = api::ToProto(sample);
                              return send(chunk);
                            });
}

absl::Status RunService::Upload::Accept(const v1::UploadRunRequest& message) { return assembler_.Accept(message); }

absl::StatusOr<v1::Run> RunService::Upload::Finish() {
  INSDIAG_ASSIGN_OR_RETURN(auto upload, assembler_.Finish());
  auto stored = service_.store_.Create(upload.run, upload.identity);
  if (!stored.ok()) {
    if (stored.status().code() == absl::StatusCode::kAlreadyExists) {
      return WithErrorInfo(stored.status(), "REQUEST_ID_REUSED",
                           {{"request_id", upload.identity.request_id}});
    }
    return stored.status();
  }
  return ToProto(*stored);
}

}  // namespace insdiag::server
