// The real clients against a real insdiagd on the test database: the
// `insdiag diagnose` verb (shared/spec/cli-and-report.md) and the Python
// example client (clients/python, Debian's python3-grpcio).
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <filesystem>
#include <regex>
#include <thread>

#include "support/database_fixture.h"
#include "support/subprocess.h"

namespace insdiag::testing {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;

class ClientsTest : public DatabaseTest {
 protected:
  void SetUp() override {
    DatabaseTest::SetUp();
    if (IsSkipped() || HasFatalFailure()) return;
    dir_ = MakeTempDir("insdiag-clients");
    std::filesystem::create_directories(dir_ / "server");
    auto server = Subprocess::Start({INSDIAGD_PATH, "--database-url", database_url(), "--grpc-port", "0",
                                     "--http-port", "0", "--bind", "127.0.0.1", "--workers", "1",
                                     "--fleet-refresh-seconds", "0"},
                                    dir_ / "server");
    ASSERT_TRUE(server.ok()) << server.status();
    server_ = std::make_unique<Subprocess>(std::move(*server));
    const std::regex listening(R"(listening grpc=[^ ]*:(\d+))");
    for (int i = 0; i < 400 && address_.empty(); ++i) {
      std::smatch match;
      const std::string out = server_->Stdout();
      if (std::regex_search(out, match, listening)) address_ = "127.0.0.1:" + match[1].str();
      std::this_thread::sleep_for(25ms);
    }
    ASSERT_FALSE(address_.empty()) << server_->Stderr();
    auto simulated = RunToCompletion({INSDIAG_CLI_PATH, "simulate", (dir_ / "run.csv").string(), "--profile", "static",
                                      "--rate", "10", "--seed", "5", "--serial", "INS-CLI-1"},
                                     dir_, 60s);
    ASSERT_TRUE(simulated.ok() && simulated->exit_status == 0) << simulated->stderr_text;
  }
  void TearDown() override {
    if (server_) {
      server_->Signal(SIGTERM);
      server_->Wait(20s);
    }
    server_.reset();
    DatabaseTest::TearDown();
  }
  std::filesystem::path dir_;
  std::unique_ptr<Subprocess> server_;
  std::string address_;
};

TEST_F(ClientsTest, InsdiagDiagnosePrintsTheDiagnosisJsonOfTheContract) {
  auto done = RunToCompletion({INSDIAG_CLI_PATH, "diagnose", (dir_ / "run.csv").string(), "--server", address_, "--json"},
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
                               (dir_ / "run.csv").string(), "--server", address_, "--json", "--stubs-dir",
                               (dir_ / "stubs").string()},
                              dir_, 180s);
  ASSERT_TRUE(done.ok());
  EXPECT_EQ(done->exit_status, 0) << done->stderr_text;
  EXPECT_THAT(done->stdout_text, HasSubstr("\"candidates\""));
  EXPECT_THAT(done->stdout_text, HasSubstr("\"module\": \"healthy\""));
  EXPECT_THAT(done->stderr_text, HasSubstr("uploaded runs/"));
}

}  // namespace
}  // namespace insdiag::testing
