// A hostile client against the real insdiagd on the test database: a bounded
// burst of every kind of request that once crashed, stalled or fooled the
// server (issue 61), each refused with a 4xx naming what was wrong while the
// server keeps answering; then the normal workflow (upload, analyse,
// diagnose, list) succeeds, and every run stored before is intact.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <regex>

#include "insdiag/api/json.h"
#include "insdiag/benchrun/bench_run_csv.h"
#include "insdiag/v1/runs.pb.h"
#include "support/database_fixture.h"
#include "support/insdiagd_fixture.h"
#include "support/subprocess.h"
#include "support/synthetic_run.h"

// Last: httplib.h pulls in <resolv.h>, whose `_res` macro breaks Eigen.
#include <httplib.h>

namespace insdiag::testing {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;
using ::testing::Not;

// How many times the burst is sent: enough to catch a refusal that leaks or
// wedges something, few enough for the e2e suite.
constexpr int kBurstRounds = 3;

class HostileClientTest : public ServerProcessTest {
 protected:
  void SetUp() override {
    DatabaseTest::SetUp();
    if (IsSkipped() || HasFatalFailure()) return;
    StartServer(INSDIAGD_PATH, "insdiag-hostile");
    if (HasFatalFailure()) return;
    http_ = std::make_unique<httplib::Client>("127.0.0.1", http_port_);
    http_->set_read_timeout(60s);
    http_->set_bearer_token_auth(token_.c_str());
  }

  // The refusal of one hostile request: its status and what its body names.
  void ExpectRefused(const httplib::Result& response, int status, const std::string& names, const std::string& what) {
    ASSERT_TRUE(response) << what << ": no answer (the server may have crashed)";
    EXPECT_EQ(response->status, status) << what << ": " << response->body.substr(0, 400);
    EXPECT_THAT(response->body, HasSubstr(names)) << what;
    EXPECT_THAT(response->body, Not(HasSubstr("SELECT"))) << what;
    EXPECT_THAT(response->body, Not(HasSubstr("INSERT"))) << what;
    auto health = http_->Get("/healthz");
    ASSERT_TRUE(health && health->status == 200) << "the server stopped answering after: " << what;
  }

  httplib::Result PostCsv(const std::string& csv, const std::string& filename) {
    return http_->Post(("/v1/runs:upload?filename=" + filename).c_str(), csv, "text/csv");
  }

  // One round of every hostile case.
  void SendBurst(const std::string& run_name) {
    for (const std::string bad : {"Bearer \xff", "Bearer \x01\x02" "abc", "Bearer caf\xc3\xa9"}) {
      httplib::Client raw("127.0.0.1", http_port_);
      ExpectRefused(raw.Get("/v1/runs", {{"Authorization", bad}}), 401, "header Authorization: byte 0x", "bad token");
    }
    ExpectRefused(http_->Get("/v1/runs", {{"X-Filler", std::string(40'000, 'x')}}), 400, "header line",
                  "a header line over 8 KiB");
    httplib::Headers many;
    for (int i = 0; i < 6; ++i) many.emplace("X-Filler-" + std::to_string(i), std::string(7'000, 'x'));
    ExpectRefused(http_->Get("/v1/runs", many), 400, "headers hold", "headers over 32 KiB in all");

    const std::string good = benchrun::FormatBenchRun(SyntheticStaticRun(500, 50.0, 41));
    const std::size_t after_site = good.find("\nt,");
    std::string bomb = good;
    std::string keys;
    for (int k = 0; k < 30'000; ++k) keys += "# key_" + std::to_string(k) + ": v\n";
    bomb.insert(after_site + 1, keys);
    const auto start = std::chrono::steady_clock::now();
    auto bombed = PostCsv(bomb, "bomb.csv");
    const std::chrono::duration<double> took = std::chrono::steady_clock::now() - start;
    EXPECT_LT(took.count(), 2.0) << "a 30,000-key run took that long to refuse";
    ExpectRefused(bombed, 400, "a run holds at most 256", "metadata bomb");

    std::string huge = good;
    huge.insert(after_site + 1, "# notes: " + std::string(10'000'000, 'n') + "\n");
    ExpectRefused(PostCsv(huge, "huge.csv"), 400, "huge.csv:", "10 MB metadata value");
    std::string not_utf8 = good;
    not_utf8.insert(after_site + 1, "# shift: caf\xff\n");
    ExpectRefused(PostCsv(not_utf8, "bytes.csv"), 400, "shift: byte 0xFF is not UTF-8", "invalid UTF-8");
    std::string slash = good;
    slash.replace(slash.find("INS-2000-0042"), 13, "INS/2000");
    ExpectRefused(PostCsv(slash, "slash.csv"), 400, "holds '/'", "serial with a slash");

    ExpectRefused(http_->Post("/v1/analyses", R"({"run":")" + run_name + R"(","discover":"yes"})", "application/json"),
                  400, "discover: expected true or false", "string-coded boolean");
    ExpectRefused(http_->Post("/v1/analyses", R"({"run":")" + run_name + R"(","model":{"effects":["gyro"]}})",
                              "application/json"),
                  400, "analysis.model.effects[0]: unknown effect 'gyro'", "unknown effect");
    ExpectRefused(http_->Post("/v1/tokens", R"({"displayName":"x","role":"VIEWER","expireTime":"9999-12-31T23:59:59Z"})",
                              "application/json"),
                  400, "token.expire_time", "expiry in 9999");
    auto cli = RunToCompletion({INSDIAG_CLI_PATH, "tokens", "create", "--name", "far", "--role", "viewer",
                                "--expires-days", "1e9", "--server", address_, "--token", token_},
                               dir_, 30s);
    ASSERT_TRUE(cli.ok());
    EXPECT_EQ(cli->exit_status, 2) << cli->stderr_text;
    EXPECT_THAT(cli->stderr_text, HasSubstr("--expires-days must be"));
    EXPECT_THAT(cli->stderr_text, Not(HasSubstr("INSERT")));
  }

  std::unique_ptr<httplib::Client> http_;
};

TEST_F(HostileClientTest, ABurstOfHostileRequestsIsRefusedAndTheNormalWorkflowThenSucceedsWithEveryRunIntact) {
  std::map<std::string, std::string> sha256_of;  // the runs stored before, by name
  for (std::uint32_t seed : {51u, 52u}) {
    auto stored = PostCsv(benchrun::FormatBenchRun(SyntheticStaticRun(2'000, 50.0, seed)), "before.csv");
    ASSERT_TRUE(stored && stored->status == 200);
    v1::Run run;
    ASSERT_TRUE(api::FromJson(stored->body, &run).ok()) << stored->body;
    sha256_of[run.name()] = run.sha256();
  }
  for (int round = 0; round < kBurstRounds && !HasFatalFailure(); ++round) SendBurst(sha256_of.begin()->first);
  ASSERT_FALSE(HasFatalFailure());

  // The normal workflow: the CLI uploads, analyses and diagnoses a simulated run.
  auto simulated = RunToCompletion({INSDIAG_CLI_PATH, "simulate", (dir_ / "run.csv").string(), "--profile", "static",
                                    "--rate", "10", "--seed", "5", "--serial", "INS-HOSTILE-1"},
                                   dir_, 60s);
  ASSERT_TRUE(simulated.ok() && simulated->exit_status == 0) << simulated->stderr_text;
  auto diagnosed = RunToCompletion({INSDIAG_CLI_PATH, "diagnose", (dir_ / "run.csv").string(), "--server", address_,
                                    "--token", token_, "--json"},
                                   dir_, 180s);
  ASSERT_TRUE(diagnosed.ok());
  EXPECT_EQ(diagnosed->exit_status, 0) << diagnosed->stderr_text;
  EXPECT_THAT(diagnosed->stdout_text, HasSubstr("\"candidates\""));
  EXPECT_THAT(diagnosed->stderr_text, HasSubstr("SUCCEEDED"));

  auto listed = http_->Get("/v1/runs?pageSize=1000");
  ASSERT_TRUE(listed && listed->status == 200);
  v1::ListRunsResponse runs;
  ASSERT_TRUE(api::FromJson(listed->body, &runs).ok()) << listed->body;
  EXPECT_EQ(runs.runs_size(), static_cast<int>(sha256_of.size()) + 1) << "a hostile request stored a run";
  for (const auto& [name, sha256] : sha256_of) {
    auto got = http_->Get(("/v1/" + name).c_str());
    ASSERT_TRUE(got && got->status == 200) << name;
    v1::Run run;
    ASSERT_TRUE(api::FromJson(got->body, &run).ok());
    EXPECT_EQ(run.sha256(), sha256) << name << " changed";
  }
}

}  // namespace
}  // namespace insdiag::testing
