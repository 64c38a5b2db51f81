// Hostile requests against the in-process server, one case each, through
// real HTTP and gRPC clients: each is refused with a 4xx that names what was
// wrong, nothing is stored or queued, and the server answers afterwards.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "insdiag/api/json.h"
#include "insdiag/benchrun/bench_run_csv.h"
#include "insdiag/client/run_client.h"
#include "server_fixture.h"
#include "support/synthetic_run.h"

namespace insdiag::testing {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

class HostileInputTest : public ServerTest {
 protected:
  // The stored run a test refers to.
  v1::Run Upload(const engine::BenchRun& run) {
    auto stored = client::UploadRun(runs(), run, {});
    EXPECT_TRUE(stored.ok()) << stored.status();
    return stored.value_or(v1::Run{});
  }
  bool ServerAnswers() {
    auto health = http().Get("/healthz");
    return health && health->status == 200;
  }
};

TEST_F(HostileInputTest, AnAuthorizationHeaderOutsidePrintableAsciiIsRefusedWith401AndTheServerStaysUp) {
  for (const std::string token : {"Bearer \xff", "Bearer \x01\x02" "abc", "Bearer caf\xc3\xa9"}) {
    httplib::Client raw("127.0.0.1", server_->http_port());
    auto response = raw.Get("/v1/runs", {{"Authorization", token}});
    ASSERT_TRUE(response) << "no answer: did the server crash?";
    EXPECT_EQ(response->status, 401);
    EXPECT_THAT(response->body, HasSubstr("header Authorization: byte 0x"));
    EXPECT_THAT(response->body, HasSubstr("at position"));
  }
  EXPECT_TRUE(ServerAnswers());
}

TEST_F(HostileInputTest, RequestFieldsOfTheWrongJsonTypeOrUnknownEffectsAreRefusedBeforeAnythingIsQueued) {
  const v1::Run run = Upload(SyntheticStaticRun(3'000, 50.0, 21));
  const auto post = [&](const std::string& analysis) {
    return http().Post("/v1/analyses", analysis, "application/json");
  };
  auto yes = post(R"({"run":")" + run.name() + R"(","discover":"yes"})");
  ASSERT_TRUE(yes);
  EXPECT_EQ(yes->status, 400);
  EXPECT_THAT(yes->body, HasSubstr("discover: expected true or false"));

  auto scalar = post(R"({"run":")" + run.name() + R"(","model":{"effects":"gyro"}})");
  ASSERT_TRUE(scalar);
  EXPECT_EQ(scalar->status, 400);
  EXPECT_THAT(scalar->body, HasSubstr("model.effects: expected an array"));

  auto unknown = post(R"({"run":")" + run.name() + R"(","model":{"effects":["gyro_scale_factor","gyro"]}})");
  ASSERT_TRUE(unknown);
  EXPECT_EQ(unknown->status, 400);
  EXPECT_THAT(unknown->body, HasSubstr("analysis.model.effects[1]: unknown effect 'gyro'"));

  auto listed = http().Get("/v1/analyses");
  ASSERT_TRUE(listed);
  EXPECT_THAT(listed->body, Not(HasSubstr("analyses/"))) << "a refused analysis was queued";
}

TEST_F(HostileInputTest, TokenExpiriesOutsideTenYearsAreRefusedNamingTheFieldAndNoSqlIsShown) {
  auto far = http().Post("/v1/tokens", R"({"displayName":"far","role":"VIEWER","expireTime":"9999-12-31T23:59:59Z"})",
                         "application/json");
  ASSERT_TRUE(far);
  EXPECT_EQ(far->status, 400);
  EXPECT_THAT(far->body, HasSubstr("token.expire_time: 9999-12-31T23:59:59+00:00 is more than 3650 days"));
  auto past = http().Post("/v1/tokens", R"({"displayName":"past","role":"VIEWER","expireTime":"2001-01-01T00:00:00Z"})",
                          "application/json");
  ASSERT_TRUE(past);
  EXPECT_EQ(past->status, 400);
  EXPECT_THAT(past->body, HasSubstr("token.expire_time: must be in the future"));
  EXPECT_THAT(far->body + past->body, Not(HasSubstr("INSERT")));
  auto listed = http().Get("/v1/tokens");
  ASSERT_TRUE(listed);
  EXPECT_THAT(listed->body, Not(HasSubstr("\"far\"")));
}

TEST_F(HostileInputTest, SerialsThatCannotBeResourceNamesAreRefusedOverRestAndGrpc) {
  engine::BenchRun run = SyntheticStaticRun(1'000, 50.0, 22);
  run.metadata.unit_serial = "INS/2000";
  auto rest = http().Post("/v1/runs:upload?filename=slash.csv", benchrun::FormatBenchRun(run), "text/csv");
  ASSERT_TRUE(rest);
  EXPECT_EQ(rest->status, 400);
  EXPECT_THAT(rest->body, HasSubstr("slash.csv:2:"));
  EXPECT_THAT(rest->body, HasSubstr("unit_serial: 'INS/2000' holds '/'"));
  auto grpc = client::UploadRun(runs(), run, {});
  EXPECT_EQ(grpc.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(grpc.status().message(), HasSubstr("metadata.unit_serial"));
  EXPECT_EQ(StoredRunCount(), 0);
}

TEST_F(HostileInputTest, MetadataThatIsNotUtf8IsRefusedNamingLineAndField) {
  std::string csv = benchrun::FormatBenchRun(SyntheticStaticRun(1'000, 50.0, 23));
  csv.insert(csv.find("# site_height_m"), "# shift: caf\xff\n");
  auto response = http().Post("/v1/runs:upload?filename=bytes.csv", csv, "text/csv");
  ASSERT_TRUE(response);
  EXPECT_EQ(response->status, 400);
  EXPECT_THAT(response->body, HasSubstr("shift: byte 0xFF is not UTF-8 text"));
  EXPECT_THAT(response->body, HasSubstr("bytes.csv:"));
  EXPECT_EQ(StoredRunCount(), 0);
}

// A run at the metadata limits is about 1 MiB of free metadata: pages of
// them list as summaries, and GetRun still returns all of it.
TEST_F(HostileInputTest, ListingsCarrySummariesSoThatRunsAtTheMetadataLimitsNeverBreakThem) {
  engine::BenchRun run = SyntheticStaticRun(1'000, 50.0, 24);
  for (std::size_t k = run.metadata.extra.size(); k < benchrun::kMaxFreeMetadataKeys; ++k) {
    run.metadata.extra.emplace_back("note_" + std::to_string(k), std::string(benchrun::kMaxMetadataValueBytes, 'v'));
  }
  const int stored_count = 5;
  std::string last_name;
  for (int i = 0; i < stored_count; ++i) last_name = Upload(run).name();
  auto listed = http().Get("/v1/runs?pageSize=1000");
  ASSERT_TRUE(listed);
  EXPECT_EQ(listed->status, 200) << listed->body.substr(0, 300);
  EXPECT_LT(listed->body.size(), 64u * 1024u) << "a listing carries summaries";
  EXPECT_EQ(StoredRunCount(), stored_count);
  auto got = http().Get(("/v1/" + last_name).c_str());
  ASSERT_TRUE(got);
  v1::Run whole;
  ASSERT_TRUE(api::FromJson(got->body, &whole).ok());
  EXPECT_EQ(whole.metadata().extra_size(), static_cast<int>(benchrun::kMaxFreeMetadataKeys));
}

}  // namespace
}  // namespace insdiag::testing
