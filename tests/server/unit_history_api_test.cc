// GetUnitHistory through the real API: an in-process server over a fresh
// database holding a unit's analyses over several weeks; a real gRPC stub,
// a real HTTP client with a viewer's token, and the real insdiag CLI; and
// runs simulated, uploaded and analysed by the server's own worker.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include <absl/strings/ascii.h>
#include <absl/strings/str_format.h>

#include "insdiag/api/json.h"
#include "insdiag/v1/knowledge.grpc.pb.h"
#include "kb/evidence_reports.h"
#include "server_fixture.h"
#include "support/stored_history.h"
#include "support/subprocess.h"

namespace insdiag::testing {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;

constexpr char kSigma[] = "gyro_bias_gm.x.sigma";
constexpr int kRuns = 4;

class UnitHistoryApiTest : public ServerTest {
 protected:
  void SetUp() override {
    ServerTest::SetUp();
    if (IsSkipped() || HasFatalFailure()) return;
    viewer_token_ = MakeToken(pool(), v1::VIEWER);
  }

  // Stored before the server's workers exist, which would otherwise race the
  // store for the analyses' jobs.
  void BeforeServerStarts() override {
    // σ of gyro x growing by a fifth of nominal a week, each measured to ±5 %.
    for (int i = 0; i < kRuns; ++i) {
      v1::AnalysisReport report = kb::testing::NominalReport();
      auto* sigma = kb::testing::Identified(report, kSigma);
      sigma->set_value((1.0 + 0.2 * i) * kb::testing::Nominal(kSigma));
      sigma->set_std_error(0.05 * sigma->value());
      StoreAnalysedRun(pool(), "INS-API-1", 7.0 * i, report);
    }
  }

  std::string viewer_token_;
};

const v1::UnitParameterHistory* Find(const v1::UnitHistory& h, const std::string& name) {
  for (const auto& p : h.parameters()) {
    if (p.name() == name) return &p;
  }
  return nullptr;
}

TEST_F(UnitHistoryApiTest, GrpcReturnsTheRunsAndEachParametersTrend) {
  auto knowledge = v1::KnowledgeService::NewStub(channel());
  grpc::ClientContext context;
  v1::GetUnitHistoryRequest request;
  request.set_unit("units/INS-API-1");
  v1::UnitHistory history;
  const grpc::Status status = knowledge->GetUnitHistory(&context, request, &history);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(history.runs_size(), kRuns);
  const auto* sigma = Find(history, kSigma);
  ASSERT_NE(sigma, nullptr);
  EXPECT_EQ(sigma->points_size(), kRuns);
  // The points lie on the line: slope 0.2 × nominal per 7 days.
  EXPECT_NEAR(sigma->statistics().trend().slope_per_day(), 0.2 * kb::testing::Nominal(kSigma) / 7.0,
              1e-9 * kb::testing::Nominal(kSigma));
  EXPECT_LT(sigma->statistics().trend().p_value(), 1e-6);

  grpc::ClientContext missing_context;
  request.set_unit("units/NO-SUCH-UNIT");
  EXPECT_EQ(knowledge->GetUnitHistory(&missing_context, request, &history).error_code(), grpc::StatusCode::NOT_FOUND);
}

TEST_F(UnitHistoryApiTest, RestServesAViewerAndMapsErrors) {
  httplib::Client viewer("127.0.0.1", server_->http_port());
  viewer.set_bearer_token_auth(viewer_token_.c_str());
  auto page = viewer.Get("/v1/units/INS-API-1/history?pageSize=3");
  ASSERT_TRUE(page);
  ASSERT_EQ(page->status, 200) << page->body;
  v1::UnitHistory history;
  ASSERT_TRUE(api::FromJson(page->body, &history).ok()) << page->body;
  EXPECT_EQ(history.runs_size(), 3);
  ASSERT_FALSE(history.next_page_token().empty());
  EXPECT_THAT(page->body, HasSubstr("\"slopePerDay\""));
  auto rest = viewer.Get("/v1/units/INS-API-1/history?pageToken=" + history.next_page_token());
  ASSERT_TRUE(rest);
  ASSERT_EQ(rest->status, 200) << rest->body;
  v1::UnitHistory second;
  ASSERT_TRUE(api::FromJson(rest->body, &second).ok());
  EXPECT_EQ(second.runs_size(), 1);

  EXPECT_EQ(viewer.Get("/v1/units/NO-SUCH-UNIT/history")->status, 404);
  EXPECT_EQ(viewer.Get("/v1/units/INS-API-1/history?confidence=2")->status, 400);
  httplib::Client anonymous("127.0.0.1", server_->http_port());
  EXPECT_EQ(anonymous.Get("/v1/units/INS-API-1/history")->status, 401);
}

TEST_F(UnitHistoryApiTest, TheCliPrintsATablePerParameterAndTheJson) {
  const auto dir = MakeTempDir("insdiag-history-cli");
  const std::string address = "127.0.0.1:" + std::to_string(server_->grpc_port());
  auto table = RunToCompletion({INSDIAG_CLI_PATH, "history", "INS-API-1", "--server", address, "--token", viewer_token_},
                               dir, 60s);
  ASSERT_TRUE(table.ok()) << table.status();
  EXPECT_EQ(table->exit_status, 0) << table->stderr_text;
  EXPECT_THAT(table->stdout_text, HasSubstr("units/INS-API-1 (unitTypes/INS-2000): 4 runs, 4 analysed"));
  EXPECT_THAT(table->stdout_text, HasSubstr("run-to-run sd"));
  EXPECT_THAT(table->stdout_text, HasSubstr(kSigma));
  auto json = RunToCompletion({INSDIAG_CLI_PATH, "history", "units/INS-API-1", "--json", "--parameter", kSigma,
                               "--server", address, "--token", viewer_token_},
                              dir, 60s);
  ASSERT_TRUE(json.ok()) << json.status();
  EXPECT_EQ(json->exit_status, 0) << json->stderr_text;
  v1::UnitHistory history;
  ASSERT_TRUE(api::FromJson(json->stdout_text, &history).ok()) << json->stdout_text;
  ASSERT_EQ(history.parameters_size(), 1);
  EXPECT_EQ(history.parameters(0).points_size(), kRuns);
  auto unknown = RunToCompletion({INSDIAG_CLI_PATH, "history", "NO-SUCH-UNIT", "--server", address, "--token",
                                  viewer_token_}, dir, 60s);
  ASSERT_TRUE(unknown.ok());
  EXPECT_EQ(unknown->exit_status, 1);
  EXPECT_THAT(unknown->stderr_text, HasSubstr("NOT_FOUND"));
}

// The whole chain on the engine's own numbers: four one-hour static runs of
// one unit simulated with gyro x's angle random walk growing from run to
// run, uploaded, analysed by the server's worker and diagnosed.
TEST_F(UnitHistoryApiTest, RunsAnalysedByTheServerGiveTheHistoryOfWhatTheEngineIdentified) {
  const auto dir = MakeTempDir("insdiag-history-engine");
  const std::string address = "127.0.0.1:" + std::to_string(server_->grpc_port());
  const double arw = kb::testing::Nominal("gyro_arw.x");
  const std::vector<double> factors = {1.0, 1.15, 1.3, 1.45};
  auto analyses = v1::AnalysisService::NewStub(channel());
  std::string last;
  for (std::size_t i = 0; i < factors.size(); ++i) {
    const std::string csv = (dir / ("run" + std::to_string(i) + ".csv")).string();
    auto simulated = RunToCompletion({INSDIAG_CLI_PATH, "simulate", "--profile", "static", "--rate", "10", "--seed",
                                      std::to_string(3 + i), "--serial", "INS-ENGINE-1", "--param",
                                      absl::StrFormat("gyro_arw.x=%.9g", factors[i] * arw), csv},
                                     dir, 60s);
    ASSERT_TRUE(simulated.ok() && simulated->exit_status == 0) << (simulated.ok() ? simulated->stderr_text : "");
    // Tested two months apart: the history spaces the runs by their started_at.
    {
      std::ifstream in(csv);
      std::stringstream text;
      text << in.rdbuf();
      std::string body = text.str();
      const std::size_t after_format = body.find('\n') + 1;
      body.insert(after_format, absl::StrFormat("# started_at: 2026-0%d-01T08:00:00Z\n", 1 + 2 * i));
      std::ofstream(csv, std::ios::trunc) << body;
    }
    auto uploaded = RunToCompletion({INSDIAG_CLI_PATH, "upload", csv, "--server", address, "--token", admin_token_},
                                    dir, 60s);
    ASSERT_TRUE(uploaded.ok() && uploaded->exit_status == 0) << (uploaded.ok() ? uploaded->stderr_text : "");
    grpc::ClientContext create_context;
    v1::CreateAnalysisRequest create;
    create.mutable_analysis()->set_run(std::string(absl::StripAsciiWhitespace(uploaded->stdout_text)));
    v1::Analysis analysis;
    ASSERT_TRUE(analyses->CreateAnalysis(&create_context, create, &analysis).ok());
    grpc::ClientContext watch_context;
    watch_context.set_deadline(std::chrono::system_clock::now() + 240s);
    v1::WatchAnalysisRequest watch;
    watch.set_name(analysis.name());
    auto reader = analyses->WatchAnalysis(&watch_context, watch);
    while (reader->Read(&analysis)) {
    }
    ASSERT_TRUE(reader->Finish().ok());
    ASSERT_EQ(analysis.state(), v1::Analysis::SUCCEEDED) << analysis.error().message();
    last = analysis.name();
  }
  auto knowledge = v1::KnowledgeService::NewStub(channel());
  grpc::ClientContext context;
  v1::GetUnitHistoryRequest request;
  request.set_unit("units/INS-ENGINE-1");
  request.add_parameters("gyro_arw.x");
  v1::UnitHistory history;
  ASSERT_TRUE(knowledge->GetUnitHistory(&context, request, &history).ok());
  ASSERT_EQ(history.parameters_size(), 1);
  const v1::UnitParameterHistory& p = history.parameters(0);
  ASSERT_EQ(p.points_size(), 4);
  for (int i = 0; i < 4; ++i) {
    // Each run's identified value within 4 SE of what was simulated.
    EXPECT_NEAR(p.points(i).value(), factors[i] * arw, 4.0 * p.points(i).std_error()) << i;
  }
  EXPECT_GT(p.statistics().trend().slope_per_day(), 0.0);
  EXPECT_LT(p.statistics().trend().p_value(), 1e-3);

  grpc::ClientContext diagnose_context;
  v1::CreateDiagnosisRequest diagnose;
  diagnose.set_analysis(last);
  v1::Diagnosis diagnosis;
  ASSERT_TRUE(knowledge->CreateDiagnosis(&diagnose_context, diagnose, &diagnosis).ok());
  EXPECT_THAT(diagnosis.notes(), ::testing::Contains(HasSubstr("significant trends in gyro_arw.x")));
  bool counted = false;
  for (const auto& e : diagnosis.evidence()) counted = counted || e.name() == "gyro_arw.x.trend";
  EXPECT_TRUE(counted) << diagnosis.DebugString();
}

}  // namespace
}  // namespace insdiag::testing
