// RunService over REST/JSON, through a real HTTP client against the
// in-process server.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <absl/strings/str_split.h>

#include "insdiag/api/json.h"
#include "insdiag/api/run_codec.h"
#include "insdiag/benchrun/bench_run_csv.h"
#include "insdiag/client/run_client.h"
#include "server_fixture.h"
#include "support/synthetic_run.h"

namespace insdiag::testing {
namespace {

using ::testing::HasSubstr;

class RunsRestTest : public ServerTest {
 protected:
  v1::Run PostCsv(const std::string& csv, const std::string& query = "") {
    auto response = http().Post(("/v1/runs:upload" + query).c_str(), csv, "text/csv");
    EXPECT_TRUE(response) << "no HTTP response";
    if (!response) return {};
    EXPECT_EQ(response->status, 200) << response->body;
    v1::Run run;
    EXPECT_TRUE(api::FromJson(response->body, &run).ok()) << response->body;
    return run;
  }
};

// A multi-position test (format 2) keeps its segments through a CSV upload,
// the store, GetRun and the download; and through a gRPC upload.
TEST_F(RunsRestTest, SegmentedTestRoundTripsOverRestAndGrpc) {
  auto run = SyntheticStaticRun(3'000, 50.0, 6);
  run.metadata.format = std::string(benchrun::kFormatV2);
  run.metadata.segment_starts = {1'000, 2'000};
  const v1::Run stored = PostCsv(benchrun::FormatBenchRun(run), "?requestId=rest-segments");
  EXPECT_THAT(stored.metadata().segment_starts(), ::testing::ElementsAre(1'000, 2'000));
  EXPECT_EQ(stored.metadata().format(), "insdiag-bench-run/2");
  auto download = http().Get(("/v1/" + stored.name() + ":download").c_str());
  ASSERT_TRUE(download);
  auto back = benchrun::ParseBenchRun(download->body, "download");
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->metadata.segment_starts, run.metadata.segment_starts);
  EXPECT_EQ(back->metadata.extra, run.metadata.extra);

  auto over_grpc = client::UploadRun(runs(), run, client::UploadOptions{.request_id = "grpc-segments"});
  ASSERT_TRUE(over_grpc.ok()) << over_grpc.status();
  EXPECT_THAT(over_grpc->metadata().segment_starts(), ::testing::ElementsAre(1'000, 2'000));
}

TEST_F(RunsRestTest, CsvUploadRoundTrips) {
  const auto run = SyntheticStaticRun(30'000, 50.0, 5);
  const std::string csv = benchrun::FormatBenchRun(run);
  const v1::Run stored = PostCsv(csv, "?requestId=rest-1");
  EXPECT_EQ(stored.sample_count(), 30'000);
  EXPECT_EQ(stored.sha256(), api::SampleSha256(run));
  EXPECT_EQ(stored.metadata().request_id(), "rest-1");

  auto got = http().Get(("/v1/" + stored.name()).c_str());
  ASSERT_TRUE(got);
  EXPECT_EQ(got->status, 200);
  v1::Run fetched;
  ASSERT_TRUE(api::FromJson(got->body, &fetched).ok()) << got->body;
  EXPECT_EQ(fetched.name(), stored.name());
  EXPECT_THAT(got->body, HasSubstr(R"("unitSerial":"INS-2000-0042")"));

  auto download = http().Get(("/v1/" + stored.name() + ":download").c_str());
  ASSERT_TRUE(download);
  EXPECT_EQ(download->status, 200);
  EXPECT_EQ(download->get_header_value("Content-Type"), "text/csv");
  auto back = benchrun::ParseBenchRun(download->body, "download");
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(api::SampleSha256(*back), stored.sha256());
  EXPECT_EQ(back->metadata.extra, run.metadata.extra);
}

TEST_F(RunsRestTest, BadCsvIsRefusedNamingLineAndColumnAndStoresNothing) {
  auto run = SyntheticStaticRun(100, 50.0, 5);
  std::string csv = benchrun::FormatBenchRun(run);
  // Spoil the third data row's second field (gyro_x).
  std::size_t at = csv.find("\nt,");
  for (int row = 0; row < 3; ++row) at = csv.find('\n', at + 1);
  const std::size_t field = csv.find(',', at) + 1;
  csv.replace(field, csv.find(',', field) - field, "1.2.3");
  const int line = static_cast<int>(std::count(csv.begin(), csv.begin() + static_cast<std::ptrdiff_t>(field), '\n')) + 1;
  const int column = static_cast<int>(field - at);

  auto response = http().Post("/v1/runs:upload?filename=run.csv", csv, "text/csv");
  ASSERT_TRUE(response);
  EXPECT_EQ(response->status, 400);
  const std::string where = "run.csv:" + std::to_string(line) + ":" + std::to_string(column);
  EXPECT_THAT(response->body, HasSubstr(where)) << "the refusal names line and column";
  EXPECT_THAT(response->body, HasSubstr(R"("status":"INVALID_ARGUMENT")"));
  EXPECT_THAT(response->body, HasSubstr("google.rpc.BadRequest"));
  EXPECT_EQ(StoredRunCount(), 0);
}

TEST_F(RunsRestTest, TruncatedCsvStoresNothing) {
  const std::string csv = benchrun::FormatBenchRun(SyntheticStaticRun(1'000, 50.0, 5));
  // Cut in the middle of a row: that row has too few fields.
  auto response = http().Post("/v1/runs:upload", csv.substr(0, csv.size() / 2 + 7), "text/csv");
  ASSERT_TRUE(response);
  EXPECT_EQ(response->status, 400) << response->body;
  EXPECT_EQ(StoredRunCount(), 0);
}

TEST_F(RunsRestTest, NdjsonUploadUsesTheSameStreamAsGrpc) {
  const auto run = SyntheticStaticRun(500, 50.0, 9);
  std::string body;
  api::ForEachUploadRequest(run, "nd-1", 200, [&](const v1::UploadRunRequest& request) {
    body += *api::ToJson(request) + "\n";
    return true;
  });
  auto response = http().Post("/v1/runs:upload", body, "application/x-ndjson");
  ASSERT_TRUE(response);
  EXPECT_EQ(response->status, 200) << response->body;
  EXPECT_THAT(response->body, HasSubstr(R"("sampleCount":"500")"));
}

TEST_F(RunsRestTest, ListPaginatesGetAndDeleteMapErrors) {
  std::vector<std::string> names;
  for (std::uint32_t seed = 0; seed < 3; ++seed) {
    names.push_back(PostCsv(benchrun::FormatBenchRun(SyntheticStaticRun(10, 50.0, seed))).name());
  }
  auto first = http().Get("/v1/runs?pageSize=2");
  ASSERT_TRUE(first);
  v1::ListRunsResponse page;
  ASSERT_TRUE(api::FromJson(first->body, &page).ok()) << first->body;
  ASSERT_EQ(page.runs_size(), 2);
  auto second = http().Get(("/v1/runs?page_size=2&pageToken=" + page.next_page_token()).c_str());
  ASSERT_TRUE(second);
  v1::ListRunsResponse rest;
  ASSERT_TRUE(api::FromJson(second->body, &rest).ok()) << second->body;
  ASSERT_EQ(rest.runs_size(), 1);
  EXPECT_EQ(rest.runs(0).name(), names[0]);
  EXPECT_THAT(second->body, HasSubstr(R"("nextPageToken":"")")) << "defaults are printed";

  auto removed = http().Delete(("/v1/" + names[1]).c_str());
  ASSERT_TRUE(removed);
  EXPECT_EQ(removed->status, 200);
  EXPECT_EQ(removed->body, "{}");
  auto missing = http().Get(("/v1/" + names[1]).c_str());
  ASSERT_TRUE(missing);
  EXPECT_EQ(missing->status, 404);
  EXPECT_THAT(missing->body, HasSubstr(R"("status":"NOT_FOUND")"));

  auto unknown_parameter = http().Get("/v1/runs?pageSise=2");
  ASSERT_TRUE(unknown_parameter);
  EXPECT_EQ(unknown_parameter->status, 400);
  EXPECT_THAT(unknown_parameter->body, HasSubstr("pageSise"));
  auto no_route = http().Get("/v2/runs");
  ASSERT_TRUE(no_route);
  EXPECT_EQ(no_route->status, 404);
}

TEST_F(RunsRestTest, SamplesStreamAsNewlineDelimitedJson) {
  const v1::Run stored = PostCsv(benchrun::FormatBenchRun(SyntheticStaticRun(250, 50.0, 3)));
  auto response = http().Get(("/v1/" + stored.name() + "/samples?chunkSize=100").c_str());
  ASSERT_TRUE(response);
  EXPECT_EQ(response->status, 200);
  EXPECT_EQ(response->get_header_value("Content-Type"), "application/x-ndjson");
  std::vector<std::string> lines = absl::StrSplit(response->body, '\n', absl::SkipEmpty());
  ASSERT_EQ(lines.size(), 3u);
  v1::SampleChunk last;
  ASSERT_TRUE(api::FromJson(lines[2], &last).ok()) << lines[2];
  EXPECT_EQ(last.samples_size(), 50);
}

TEST_F(RunsRestTest, HealthAndAnalysesOverRest) {
  auto health = http().Get("/healthz");
  ASSERT_TRUE(health);
  EXPECT_EQ(health->status, 200);
  EXPECT_EQ(health->body, R"({"status":"SERVING"})");
  auto analysis = http().Post("/v1/analyses", R"({"run":"runs/x"})", "application/json");
  ASSERT_TRUE(analysis);
  EXPECT_EQ(analysis->status, 400);
  EXPECT_THAT(analysis->body, HasSubstr(R"("status":"INVALID_ARGUMENT")"));
  EXPECT_THAT(analysis->body, HasSubstr("analysis.run"));
}

}  // namespace
}  // namespace insdiag::testing
