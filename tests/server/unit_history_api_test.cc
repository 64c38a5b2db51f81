// GetUnitHistory through the real API: an in-process server over a fresh
// database holding a unit's analyses over several weeks; a real gRPC stub,
// a real HTTP client with a viewer's token, and the real insdiag CLI.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

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
    // σ of gyro x growing by a fifth of nominal a week, each measured to ±5 %.
    for (int i = 0; i < kRuns; ++i) {
      v1::AnalysisReport report = kb::testing::NominalReport();
      auto* sigma = kb::testing::Identified(report, kSigma);
      sigma->set_value((1.0 + 0.2 * i) * kb::testing::Nominal(kSigma));
      sigma->set_std_error(0.05 * sigma->value());
      StoreAnalysedRun(pool(), "INS-API-1", 7.0 * i, report);
    }
    viewer_token_ = MakeToken(pool(), v1::VIEWER);
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

}  // namespace
}  // namespace insdiag::testing
