// RunService over gRPC, through a real stub against the in-process server.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <functional>
#include <optional>
#include <thread>

#include "google/rpc/error_details.pb.h"
#include "google/rpc/status.pb.h"
#include "insdiag/api/run_codec.h"
#include "server_fixture.h"
#include "support/poll.h"
#include "support/synthetic_run.h"

namespace insdiag::testing {
namespace {

using ::testing::HasSubstr;

client::UploadOptions WithRequestId(std::string request_id) {
  client::UploadOptions options;
  options.request_id = std::move(request_id);
  return options;
}

std::vector<engine::ImuSample> ReadBack(v1::RunService::Stub& stub, const std::string& name) {
  grpc::ClientContext context;
  v1::ReadRunSamplesRequest request;
  request.set_name(name);
  auto reader = stub.ReadRunSamples(&context, request);
  std::vector<engine::ImuSample> samples;
  v1::SampleChunk chunk;
  while (reader->Read(&chunk)) {
    for (const auto& sample : chunk.samples()) samples.push_back(api::FromProto(sample));
  }
  const grpc::Status status = reader->Finish();
  EXPECT_TRUE(status.ok()) << status.error_message();
  return samples;
}

// Uploads `run` with every message passed through `edit`, which may change
// it or drop it (nullopt); returns the server's verdict.
grpc::Status UploadEdited(
    v1::RunService::Stub& stub, const engine::BenchRun& run, std::size_t chunk_samples,
    const std::function<std::optional<v1::UploadRunRequest>(const v1::UploadRunRequest&)>& edit) {
  grpc::ClientContext context;
  v1::Run response;
  auto stream = stub.UploadRun(&context, &response);
  api::ForEachUploadRequest(run, "", chunk_samples, [&](const v1::UploadRunRequest& request) {
    const auto edited = edit(request);
    return !edited || stream->Write(*edited);
  });
  stream->WritesDone();
  return stream->Finish();
}

template <typename Detail>
Detail DetailOf(const grpc::Status& status) {
  google::rpc::Status details;
  details.ParseFromString(status.error_details());
  Detail detail;
  for (const auto& any : details.details()) {
    if (any.Is<Detail>()) any.UnpackTo(&detail);
  }
  return detail;
}

class RunsGrpcTest : public ServerTest {};

TEST_F(RunsGrpcTest, MillionSampleUploadRoundTripsBitExactly) {
  const auto run = SyntheticStaticRun(1'000'000, 100.0, 42);
  auto stored = client::UploadRun(runs(), run, WithRequestId("million"));
  ASSERT_TRUE(stored.ok()) << stored.status();
  EXPECT_THAT(stored->name(), ::testing::StartsWith("runs/"));
  EXPECT_EQ(stored->sample_count(), 1'000'000);
  EXPECT_EQ(stored->sha256(), api::SampleSha256(run));
  EXPECT_NEAR(stored->duration_s(), 10'000.0, 1e-6);
  EXPECT_EQ(stored->metadata().unit_serial(), "INS-2000-0042");

  grpc::ClientContext context;
  v1::GetRunRequest get;
  get.set_name(stored->name());
  v1::Run fetched;
  ASSERT_TRUE(runs().GetRun(&context, get, &fetched).ok());
  EXPECT_EQ(fetched.sha256(), stored->sha256());

  const auto samples = ReadBack(runs(), stored->name());
  ASSERT_EQ(samples.size(), run.samples.size());
  api::SampleDigest digest(true);
  for (const auto& sample : samples) digest.Add(sample);
  EXPECT_EQ(digest.HexDigest(), stored->sha256()) << "samples came back changed";
}

TEST_F(RunsGrpcTest, StreamCutOffHalfWayStoresNothing) {
  const auto run = SyntheticStaticRun(50'000, 50.0, 1);
  {
    grpc::ClientContext context;
    v1::Run response;
    auto stream = runs().UploadRun(&context, &response);
    int sent = 0;
    api::ForEachUploadRequest(run, "cut", 5'000, [&](const v1::UploadRunRequest& request) {
      return ++sent <= 5 && stream->Write(request);  // metadata + 4 of 10 chunks
    });
    context.TryCancel();
    EXPECT_EQ(stream->Finish().error_code(), grpc::StatusCode::CANCELLED);
  }
  // A complete upload afterwards is stored alone: the cut one left nothing.
  ASSERT_TRUE(client::UploadRun(runs(), SyntheticStaticRun(100, 50.0, 2), WithRequestId("whole")).ok());
  // Nothing of the cut stream turns up later, while its call winds down.
  EXPECT_TRUE(testing::HoldsThroughout([&] { return StoredRunCount() == 1; }, std::chrono::milliseconds(300)))
      << "stored runs: " << StoredRunCount();
}

TEST_F(RunsGrpcTest, StreamEndingWithoutItsDigestStoresNothing) {
  const grpc::Status status = UploadEdited(runs(), SyntheticStaticRun(1'000, 50.0, 1), 100,
                                           [](const v1::UploadRunRequest& request) {
                                             return request.has_sha256() ? std::nullopt : std::optional(request);
                                           });
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("without its sha256"));
  EXPECT_EQ(StoredRunCount(), 0);
}

TEST_F(RunsGrpcTest, WrongSha256IsRefusedAndStoresNothing) {
  const grpc::Status status = UploadEdited(runs(), SyntheticStaticRun(1'000, 50.0, 1), 100,
                                           [](v1::UploadRunRequest request) {
                                             if (request.has_sha256()) request.set_sha256(std::string(64, '0'));
                                             return std::optional(request);
                                           });
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("sha256 mismatch"));
  EXPECT_EQ(DetailOf<google::rpc::ErrorInfo>(status).reason(), "SHA256_MISMATCH");
  EXPECT_EQ(StoredRunCount(), 0);
}

TEST_F(RunsGrpcTest, SameRequestIdTwiceStoresOneRun) {
  const auto run = SyntheticStaticRun(2'000, 50.0, 1);
  auto first = client::UploadRun(runs(), run, WithRequestId("retry-me"));
  auto second = client::UploadRun(runs(), run, WithRequestId("retry-me"));
  ASSERT_TRUE(first.ok()) << first.status();
  ASSERT_TRUE(second.ok()) << second.status();
  EXPECT_EQ(first->name(), second->name());
  EXPECT_EQ(StoredRunCount(), 1);
}

TEST_F(RunsGrpcTest, SameRequestIdWithOtherContentIsAlreadyExists) {
  ASSERT_TRUE(client::UploadRun(runs(), SyntheticStaticRun(2'000, 50.0, 1), WithRequestId("reused")).ok());
  auto other = client::UploadRun(runs(), SyntheticStaticRun(2'000, 50.0, 2), WithRequestId("reused"));
  ASSERT_FALSE(other.ok());
  EXPECT_EQ(other.status().code(), absl::StatusCode::kAlreadyExists);
  EXPECT_EQ(StoredRunCount(), 1);
}

TEST_F(RunsGrpcTest, RefusedSampleIsNamedByItsFieldPath) {
  auto run = SyntheticStaticRun(2'000, 50.0, 1);
  run.samples[1234].gyro_rad_s.y() = 40.0;  // beyond ±35 rad/s
  const grpc::Status status =
      UploadEdited(runs(), run, 500, [](const v1::UploadRunRequest& request) { return std::optional(request); });
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  const auto bad_request = DetailOf<google::rpc::BadRequest>(status);
  ASSERT_EQ(bad_request.field_violations_size(), 1);
  EXPECT_EQ(bad_request.field_violations(0).field(), "samples[1234].gyro_y");
  EXPECT_EQ(StoredRunCount(), 0);
}

TEST_F(RunsGrpcTest, MessagesOutOfOrderAreRefused) {
  grpc::ClientContext context;
  v1::Run response;
  auto stream = runs().UploadRun(&context, &response);
  v1::UploadRunRequest samples_first;
  samples_first.mutable_samples()->add_samples()->set_t(1.0);
  stream->Write(samples_first);
  stream->WritesDone();
  const grpc::Status status = stream->Finish();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("before the upload's metadata"));
}

TEST_F(RunsGrpcTest, GetListDeleteAndNotFound) {
  std::vector<std::string> names;
  for (std::uint32_t seed = 0; seed < 3; ++seed) {
    auto stored = client::UploadRun(runs(), SyntheticStaticRun(10, 50.0, seed), WithRequestId(""));
    ASSERT_TRUE(stored.ok()) << stored.status();
    names.push_back(stored->name());
  }
  grpc::ClientContext list_context;
  v1::ListRunsRequest list;
  list.set_page_size(2);
  v1::ListRunsResponse page;
  ASSERT_TRUE(runs().ListRuns(&list_context, list, &page).ok());
  ASSERT_EQ(page.runs_size(), 2);
  EXPECT_EQ(page.runs(0).name(), names[2]) << "newest first";
  EXPECT_FALSE(page.next_page_token().empty());

  grpc::ClientContext delete_context;
  v1::DeleteRunRequest remove;
  remove.set_name(names[0]);
  google::protobuf::Empty empty;
  ASSERT_TRUE(runs().DeleteRun(&delete_context, remove, &empty).ok());
  grpc::ClientContext get_context;
  v1::GetRunRequest get;
  get.set_name(names[0]);
  v1::Run gone;
  EXPECT_EQ(runs().GetRun(&get_context, get, &gone).error_code(), grpc::StatusCode::NOT_FOUND);
  grpc::ClientContext bad_context;
  get.set_name("units/x");
  EXPECT_EQ(runs().GetRun(&bad_context, get, &gone).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

TEST_F(RunsGrpcTest, AnalysisServiceRefusesAMalformedName) {
  auto analyses = v1::AnalysisService::NewStub(channel());
  grpc::ClientContext context;
  v1::GetAnalysisRequest request;
  request.set_name("analyses/a");
  v1::Analysis analysis;
  EXPECT_EQ(analyses->GetAnalysis(&context, request, &analysis).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

}  // namespace
}  // namespace insdiag::testing
