// The test report end to end: a run with a hidden gyro scale factor,
// uploaded, analysed and diagnosed by a real insdiagd (on a database of the
// throwaway cluster) through the real CLI; its PDF report written by
// `insdiag report --format pdf`, rendered back by poppler and read; the same
// report, PDF and HTML, through the REST route with a viewer's token.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <regex>

#include "insdiag/api/json.h"
#include "insdiag/v1/analyses.pb.h"
#include "insdiag/v1/knowledge.pb.h"
#include "support/insdiagd_fixture.h"
#include "support/pdf_check.h"
#include "support/subprocess.h"

// Last: httplib.h pulls in <resolv.h>, whose `_res` macro breaks Eigen.
#include <httplib.h>

namespace insdiag::testing {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;
using ::testing::StartsWith;

// What the hidden effect is and how large: 100 ppm on gyro z, which the
// loop finds on a rotations profile (the demonstration's DEMO-2).
constexpr char kHiddenEffect[] = "gyro_scale_factor.z";

class TestReportTest : public ServerProcessTest {
 protected:
  void SetUp() override {
    DatabaseTest::SetUp();
    if (IsSkipped() || HasFatalFailure()) return;
    StartServer(INSDIAGD_PATH, "insdiag-test-report");
  }

  Completed Insdiag(std::vector<std::string> args, std::chrono::seconds timeout = 60s) {
    args.insert(args.begin(), INSDIAG_CLI_PATH);
    for (const std::string& a : {std::string("--server"), address_, std::string("--token"), token_}) {
      args.push_back(a);
    }
    auto done = RunToCompletion(args, dir_, timeout);
    EXPECT_TRUE(done.ok()) << done.status();
    return done.ok() ? *done : Completed{};
  }
};

TEST_F(TestReportTest, ThePdfReportOfARunWithAHiddenEffectRendersAndShowsTheEffectAndTheVerdict) {
  auto simulated = RunToCompletion({INSDIAG_CLI_PATH, "simulate", (dir_ / "run.csv").string(), "--profile",
                                    "rotations", "--rate", "10", "--seed", "12", "--serial", "RPT-E2E", "--effect",
                                    std::string(kHiddenEffect) + "=1e-4"},
                                   dir_, 60s);
  ASSERT_TRUE(simulated.ok() && simulated->exit_status == 0) << simulated->stderr_text;
  const Completed diagnosed = Insdiag({"diagnose", (dir_ / "run.csv").string(), "--json"}, 240s);
  ASSERT_EQ(diagnosed.exit_status, 0) << diagnosed.stderr_text;
  v1::Diagnosis diagnosis;
  ASSERT_TRUE(api::FromJson(diagnosed.stdout_text, &diagnosis).ok()) << diagnosed.stdout_text;
  const std::string analysis = diagnosis.analysis();

  // The verdict the analysis reached, which the document must state.
  const Completed json = Insdiag({"report", analysis, "--json"});
  ASSERT_EQ(json.exit_status, 0) << json.stderr_text;
  v1::AnalysisReport report;
  ASSERT_TRUE(api::FromJson(json.stdout_text, &report).ok()) << json.stdout_text;
  ASSERT_THAT(report.model().effects(), ::testing::Contains(kHiddenEffect)) << "the loop found the hidden effect";
  const std::string verdict = v1::AnalysisReport::Verdict_Name(report.verdict());

  const Completed written = Insdiag({"report", analysis, "--format", "pdf", "-o", (dir_ / "report.pdf").string()});
  ASSERT_EQ(written.exit_status, 0) << written.stderr_text;
  EXPECT_EQ(written.stdout_text, (dir_ / "report.pdf").string() + "\n");
  const std::string pdf = ReadFile(dir_ / "report.pdf");
  ASSERT_TRUE(CheckPdfStructure(pdf).ok()) << CheckPdfStructure(pdf);
  std::filesystem::create_directories(dir_ / "rendered");
  auto rendered = RenderBack(pdf, dir_ / "rendered");
  if (absl::IsUnavailable(rendered.status())) GTEST_SKIP() << rendered.status().message();
  ASSERT_TRUE(rendered.ok()) << rendered.status();
  ASSERT_GE(rendered->ink_fraction.size(), 3u);  // text pages and the plots
  for (const double ink : rendered->ink_fraction) EXPECT_GT(ink, 0.002) << "a blank page";
  EXPECT_THAT(rendered->text, HasSubstr("Verdict: " + verdict));
  EXPECT_TRUE(std::regex_search(rendered->text, std::regex(R"(Effects in the model\s+gyro_scale_factor\.z)")))
      << rendered->text;
  EXPECT_THAT(rendered->text, HasSubstr("RPT-E2E"));
  EXPECT_THAT(rendered->text, HasSubstr(diagnosis.candidates(0).module()));  // the diagnosis's first module
  EXPECT_THAT(rendered->text, HasSubstr("vel_n: residual"));

  // Usage the CLI refuses before asking the server.
  EXPECT_EQ(Insdiag({"report", analysis, "--format", "docx"}).exit_status, 2);
  EXPECT_EQ(Insdiag({"report", analysis, "--format", "pdf", "--json"}).exit_status, 2);
  EXPECT_EQ(Insdiag({"report", analysis, "-o", "x.pdf"}).exit_status, 2);
}

TEST_F(TestReportTest, TheRestRouteAnswersTheDocumentToAViewerAndRefusesWithoutAToken) {
  auto simulated = RunToCompletion({INSDIAG_CLI_PATH, "simulate", (dir_ / "run.csv").string(), "--profile", "static",
                                    "--rate", "10", "--seed", "3", "--serial", "RPT-REST"},
                                   dir_, 60s);
  ASSERT_TRUE(simulated.ok() && simulated->exit_status == 0) << simulated->stderr_text;
  const Completed diagnosed = Insdiag({"diagnose", (dir_ / "run.csv").string(), "--json", "--no-discover"}, 240s);
  ASSERT_EQ(diagnosed.exit_status, 0) << diagnosed.stderr_text;
  v1::Diagnosis diagnosis;
  ASSERT_TRUE(api::FromJson(diagnosed.stdout_text, &diagnosis).ok()) << diagnosed.stdout_text;
  const Completed created = Insdiag({"tokens", "create", "--name", "quality", "--role", "viewer"});
  ASSERT_EQ(created.exit_status, 0) << created.stderr_text;
  std::smatch made;
  ASSERT_TRUE(std::regex_search(created.stdout_text, made, std::regex(R"(\n(insdiag_[A-Za-z0-9_-]+)\n)")));
  const httplib::Headers viewer = {{"Authorization", "Bearer " + made[1].str()}};

  httplib::Client http("127.0.0.1", http_port_);
  const std::string path = "/v1/" + diagnosis.analysis() + ":testReport";
  auto pdf = http.Get(path + "?format=pdf", viewer);
  ASSERT_TRUE(pdf);
  EXPECT_EQ(pdf->status, 200) << pdf->body;
  EXPECT_EQ(pdf->get_header_value("Content-Type"), "application/pdf");
  EXPECT_TRUE(CheckPdfStructure(pdf->body).ok()) << CheckPdfStructure(pdf->body);

  auto html = http.Get(path, viewer);  // HTML unless asked otherwise
  ASSERT_TRUE(html);
  EXPECT_EQ(html->status, 200) << html->body;
  EXPECT_THAT(html->get_header_value("Content-Type"), StartsWith("text/html"));
  EXPECT_THAT(html->body, StartsWith("<!DOCTYPE html>"));
  EXPECT_THAT(html->body, HasSubstr("RPT-REST"));
  EXPECT_THAT(html->body, HasSubstr(diagnosis.name()));  // the analysis's diagnosis
  EXPECT_THAT(html->body, HasSubstr("<svg"));

  auto anonymous = http.Get(path + "?format=pdf");
  ASSERT_TRUE(anonymous);
  EXPECT_EQ(anonymous->status, 401);
  auto unknown_format = http.Get(path + "?format=docx", viewer);
  ASSERT_TRUE(unknown_format);
  EXPECT_EQ(unknown_format->status, 400);
  EXPECT_THAT(unknown_format->body, HasSubstr("format must be html or pdf"));
  auto missing = http.Get("/v1/analyses/00000000-0000-0000-0000-000000000000:testReport", viewer);
  ASSERT_TRUE(missing);
  EXPECT_EQ(missing->status, 404);

  // An analysis just queued (its run takes the one worker seconds) has no report yet.
  const httplib::Headers admin = {{"Authorization", "Bearer " + token_}};
  auto analysed = http.Get("/v1/" + diagnosis.analysis(), admin);
  ASSERT_TRUE(analysed && analysed->status == 200);
  v1::Analysis done;
  ASSERT_TRUE(api::FromJson(analysed->body, &done).ok());
  auto queued = http.Post("/v1/analyses", admin, "{\"run\": \"" + done.run() + "\"}", "application/json");
  ASSERT_TRUE(queued && queued->status == 200) << (queued ? queued->body : "no answer");
  v1::Analysis again;
  ASSERT_TRUE(api::FromJson(queued->body, &again).ok());
  auto early = http.Get("/v1/" + again.name() + ":testReport", viewer);
  ASSERT_TRUE(early);
  EXPECT_EQ(early->status, 400);
  EXPECT_THAT(early->body, HasSubstr("FAILED_PRECONDITION"));
  EXPECT_THAT(early->body, HasSubstr("only a SUCCEEDED analysis has a test report"));
}

}  // namespace
}  // namespace insdiag::testing
