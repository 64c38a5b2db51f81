// The real clients against a real insdiagd on the test database: the
// `insdiag diagnose` verb (shared/spec/cli-and-report.md) and the Python
// example client (clients/python, Debian's python3-grpcio).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <regex>

#include "insdiag/api/json.h"
#include "insdiag/v1/analyses.pb.h"
#include "insdiag/v1/fleet.pb.h"
#include "insdiag/v1/knowledge.pb.h"
#include "support/insdiagd_fixture.h"

namespace insdiag::testing {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;

class ClientsTest : public ServerProcessTest {
 protected:
  void SetUp() override {
    DatabaseTest::SetUp();
    if (IsSkipped() || HasFatalFailure()) return;
    StartServer(INSDIAGD_PATH, "insdiag-clients");
    if (HasFatalFailure()) return;
    http_address_ = "http://127.0.0.1:" + std::to_string(http_port_);
    auto simulated = RunToCompletion({INSDIAG_CLI_PATH, "simulate", (dir_ / "run.csv").string(), "--profile", "static",
                                      "--rate", "10", "--seed", "5", "--serial", "INS-CLI-1"},
                                     dir_, 60s);
    ASSERT_TRUE(simulated.ok() && simulated->exit_status == 0) << simulated->stderr_text;
  }
  std::string http_address_;
};

TEST_F(ClientsTest, InsdiagDiagnosePrintsTheDiagnosisJsonOfTheContract) {
  auto done = RunToCompletion({INSDIAG_CLI_PATH, "diagnose", (dir_ / "run.csv").string(), "--server", address_, "--token", token_, "--json"},
                              dir_, 120s);
  ASSERT_TRUE(done.ok());
  EXPECT_EQ(done->exit_status, 0) << done->stderr_text;
  EXPECT_THAT(done->stdout_text, HasSubstr("\"analysis\": \"analyses/"));
  EXPECT_THAT(done->stdout_text, HasSubstr("\"candidates\""));
  EXPECT_THAT(done->stdout_text, HasSubstr("\"failureMode\""));
  EXPECT_THAT(done->stdout_text, HasSubstr("\"probability\""));
  EXPECT_THAT(done->stdout_text, HasSubstr("\"evidence\""));
  EXPECT_THAT(done->stdout_text, HasSubstr("\"module\": \"healthy\""));
  EXPECT_THAT(done->stderr_text, HasSubstr("SUCCEEDED"));
  // A refused file: exit 1 naming it; bad usage: exit 2.
  auto refused = RunToCompletion({INSDIAG_CLI_PATH, "diagnose", (dir_ / "missing.csv").string(), "--server", address_},
                                 dir_, 30s);
  EXPECT_EQ(refused->exit_status, 1);
  auto usage = RunToCompletion({INSDIAG_CLI_PATH, "diagnose"}, dir_, 30s);
  EXPECT_EQ(usage->exit_status, 2);
}

TEST_F(ClientsTest, PythonClientUploadsAnalysesAndDiagnoses) {
  auto done = RunToCompletion({"/usr/bin/python3", INSDIAG_SOURCE_DIR "/clients/python/insdiag_client.py",
                               (dir_ / "run.csv").string(), "--server", address_, "--token", token_, "--json", "--stubs-dir",
                               (dir_ / "stubs").string()},
                              dir_, 180s);
  ASSERT_TRUE(done.ok());
  EXPECT_EQ(done->exit_status, 0) << done->stderr_text;
  EXPECT_THAT(done->stdout_text, HasSubstr("\"candidates\""));
  EXPECT_THAT(done->stdout_text, HasSubstr("\"module\": \"healthy\""));
  EXPECT_THAT(done->stderr_text, HasSubstr("uploaded runs/"));
}

// `insdiag tokens`: an admin makes a viewer's token; the viewer reads but may
// not upload; the refusal is in the audit trail; a revoked token is refused.
TEST_F(ClientsTest, TokensVerbMakesARoleTokenThatReadsIsRefusedAboveItsRoleAndIsRevoked) {
  const auto insdiag = [&](std::vector<std::string> args, const std::string& token) {
    args.insert(args.begin(), INSDIAG_CLI_PATH);
    for (const std::string& a : {std::string("--server"), address_, std::string("--token"), token}) args.push_back(a);
    auto done = RunToCompletion(args, dir_, 60s);
    EXPECT_TRUE(done.ok());
    return done.ok() ? *done : Completed{};
  };
  auto created = insdiag({"tokens", "create", "--name", "line 2 viewer", "--role", "viewer", "--expires-days", "30"},
                         token_);
  ASSERT_EQ(created.exit_status, 0) << created.stderr_text;
  std::smatch made;
  ASSERT_TRUE(std::regex_match(created.stdout_text, made,
                               std::regex(R"((tokens/[0-9a-f-]{36})\n(insdiag_[A-Za-z0-9_-]{43})\n)")))
      << created.stdout_text;
  const std::string name = made[1].str(), viewer = made[2].str();

  auto listed = insdiag({"tokens", "list"}, token_);
  EXPECT_EQ(listed.exit_status, 0) << listed.stderr_text;
  EXPECT_THAT(listed.stdout_text, HasSubstr("line 2 viewer"));
  EXPECT_THAT(listed.stdout_text, HasSubstr("viewer"));
  EXPECT_THAT(listed.stdout_text, ::testing::Not(HasSubstr(viewer))) << "a secret is shown only once";

  auto reads = insdiag({"fleet", "stats"}, viewer);
  EXPECT_EQ(reads.exit_status, 0) << reads.stderr_text;
  auto uploads = insdiag({"upload", (dir_ / "run.csv").string()}, viewer);
  EXPECT_EQ(uploads.exit_status, 1);
  EXPECT_THAT(uploads.stderr_text, HasSubstr("PERMISSION_DENIED"));
  auto lists_tokens = insdiag({"tokens", "list"}, viewer);
  EXPECT_EQ(lists_tokens.exit_status, 1);

  auto audit = insdiag({"tokens", "audit", "--of", name}, token_);
  EXPECT_EQ(audit.exit_status, 0) << audit.stderr_text;
  EXPECT_THAT(audit.stdout_text, HasSubstr("insdiag.v1.RunService.UploadRun"));
  EXPECT_THAT(audit.stdout_text, HasSubstr("PERMISSION_DENIED"));

  auto revoked = insdiag({"tokens", "revoke", name}, token_);
  EXPECT_EQ(revoked.exit_status, 0) << revoked.stderr_text;
  auto after = insdiag({"fleet", "stats"}, viewer);
  EXPECT_EQ(after.exit_status, 1);
  EXPECT_THAT(after.stderr_text, HasSubstr("revoked"));
}

// The server verbs of `insdiag` over a fleet written by `insdiag-fleet`
// into the server's database: statistics, Weibull, counts, ranking, trends,
// analyses and their (rebuilt) reports, diagnoses resolved, failure records;
// exit 0 / 1 (refused) / 2 (bad usage) per the contract.
TEST_F(ClientsTest, ServerVerbsReadAndResolveAGeneratedFleet) {
  auto generated = RunToCompletion({INSDIAG_FLEET_PATH, "--database-url", database_url(), "--units", "40", "--seed", "5",
                                    "--end-time", "2025-06-01", "--years", "10", "--hours-per-year", "8000"},
                                   dir_, 120s);
  ASSERT_TRUE(generated.ok());
  ASSERT_EQ(generated->exit_status, 0) << generated->stderr_text;
  EXPECT_THAT(generated->stdout_text, HasSubstr("units 40"));
  std::smatch failures_match;
  ASSERT_TRUE(std::regex_search(generated->stdout_text, failures_match, std::regex(R"(confirmed_failures (\d+))")));
  const std::string failures = failures_match[1].str();

  const auto insdiag = [&](std::vector<std::string> args) {
    args.insert(args.begin(), INSDIAG_CLI_PATH);
    args.push_back("--server");
    args.push_back(address_);
    args.push_back("--token");
    args.push_back(token_);
    auto done = RunToCompletion(args, dir_, 60s);
    EXPECT_TRUE(done.ok());
    return done.ok() ? *done : Completed{};
  };
  const auto json = [](const Completed& r, google::protobuf::Message* m) {
    const auto parsed = api::FromJson(r.stdout_text, m);
    EXPECT_TRUE(parsed.ok()) << parsed << "\n" << r.stdout_text << r.stderr_text;
  };

  auto stats = insdiag({"fleet", "stats", "--json"});
  EXPECT_EQ(stats.exit_status, 0) << stats.stderr_text;
  v1::FleetStatistics statistics;
  json(stats, &statistics);
  EXPECT_EQ(statistics.unit_count(), 40);
  EXPECT_EQ(std::to_string(statistics.failure_count()), failures);
  auto table = insdiag({"fleet", "stats"});
  EXPECT_EQ(table.exit_status, 0);
  EXPECT_THAT(table.stdout_text, HasSubstr("power_supply"));
  EXPECT_THAT(table.stdout_text, HasSubstr("MTBF"));

  auto counts = insdiag({"fleet", "counts", "--period", "year", "--json"});
  EXPECT_EQ(counts.exit_status, 0) << counts.stderr_text;
  v1::ListFailureCountsResponse counted;
  json(counts, &counted);
  EXPECT_EQ(std::to_string(counted.total()), failures);

  auto weibull = insdiag({"fleet", "weibull", "--role", "gyro.x", "--json"});
  EXPECT_EQ(weibull.exit_status, 0) << weibull.stderr_text;
  v1::WeibullFit fit;
  json(weibull, &fit);
  EXPECT_GE(fit.failures(), 2);
  EXPECT_GT(fit.shape(), 0.0);
  EXPECT_THAT(insdiag({"fleet", "weibull", "--role", "gyro.x"}).stdout_text, HasSubstr("B10"));
  EXPECT_EQ(insdiag({"fleet", "weibull"}).exit_status, 2);
  EXPECT_EQ(insdiag({"fleet", "histogram"}).exit_status, 2);
  EXPECT_EQ(insdiag({"fleet", "weibull", "--role", "flux_capacitor"}).exit_status, 1);
  EXPECT_THAT(insdiag({"fleet", "pareto"}).stdout_text, HasSubstr("cumulative"));
  EXPECT_THAT(insdiag({"fleet", "trend", "--parameter", "gyro_bias_gm.x.sigma"}).stdout_text, HasSubstr("per year"));
  EXPECT_THAT(insdiag({"fleet", "trends", "--parameter", "gyro_arw.x", "--unit", "G5-00003"}).stdout_text,
              HasSubstr("units/G5-00003"));
  auto rank = insdiag({"fleet", "rank", "--page-size", "5", "--json"});
  EXPECT_EQ(rank.exit_status, 0) << rank.stderr_text;
  v1::RankUnitsResponse ranked;
  json(rank, &ranked);
  EXPECT_EQ(ranked.units_size(), 5);

  // Analyses and their reports, rebuilt from the generated rows.
  auto listed = insdiag({"analyses", "--unit", "G5-00001", "--json"});
  EXPECT_EQ(listed.exit_status, 0) << listed.stderr_text;
  v1::ListAnalysesResponse analyses;
  json(listed, &analyses);
  ASSERT_FALSE(analyses.analyses().empty());
  auto report = insdiag({"report", analyses.analyses(0).name(), "--json"});
  EXPECT_EQ(report.exit_status, 0) << report.stderr_text;
  v1::AnalysisReport rebuilt;
  json(report, &rebuilt);
  EXPECT_EQ(rebuilt.identified_size(), 18);
  EXPECT_NE(rebuilt.verdict(), v1::AnalysisReport::VERDICT_UNSPECIFIED);
  EXPECT_THAT(insdiag({"report", analyses.analyses(0).name()}).stdout_text, HasSubstr("gyro_bias_gm.x.sigma"));
  EXPECT_EQ(insdiag({"report", "analyses/00000000-0000-4000-8000-000000000000"}).exit_status, 1);

  // The latest diagnosis of a unit, rejected: a no-fault-found record.
  auto diagnoses = insdiag({"diagnoses", "--unit", "G5-00001", "--json"});
  EXPECT_EQ(diagnoses.exit_status, 0) << diagnoses.stderr_text;
  v1::ListDiagnosesResponse listed_diagnoses;
  json(diagnoses, &listed_diagnoses);
  ASSERT_FALSE(listed_diagnoses.diagnoses().empty());
  const v1::Diagnosis& latest = listed_diagnoses.diagnoses(0);
  EXPECT_TRUE(latest.failure_record().empty());
  EXPECT_EQ(insdiag({"diagnoses", "resolve", latest.name(), "--module", "gyro.x"}).exit_status, 2);
  auto rejected = insdiag({"diagnoses", "resolve", latest.name(), "--module", "gyro.x", "--rejected"});
  EXPECT_EQ(rejected.exit_status, 0) << rejected.stderr_text;
  EXPECT_THAT(rejected.stdout_text, HasSubstr("rejected (no fault found) on gyro.x"));
  auto again = insdiag({"diagnoses", "resolve", latest.name(), "--module", "gyro.x", "--rejected"});
  EXPECT_EQ(again.exit_status, 1);
  EXPECT_THAT(again.stderr_text, HasSubstr("already resolved"));
  auto records = insdiag({"failure-records", "--unit", "G5-00001", "--module", "G5-00001/gyro.x"});
  EXPECT_EQ(records.exit_status, 0) << records.stderr_text;
  EXPECT_THAT(records.stdout_text, HasSubstr("no fault found"));
  auto created = insdiag({"failure-records", "create", "--module", "G5-00002/acc.x", "--hours", "1234",
                          "--confirmed", "--mode", "acc-bias-shift.x", "--repair-action", "module replaced"});
  EXPECT_EQ(created.exit_status, 0) << created.stderr_text;
  EXPECT_THAT(created.stdout_text, HasSubstr("failureRecords/"));
  EXPECT_EQ(insdiag({"failure-records", "create", "--module", "G5-00002/acc.x", "--confirmed"}).exit_status, 2);
}

}  // namespace
}  // namespace insdiag::testing
