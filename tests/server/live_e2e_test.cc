// Live monitoring end to end: a test from the independent bench simulator
// (tests/benchsim, not the engine's code) fed line by line over a loopback
// socket to `insdiag stream`, monitored by a real insdiagd while a viewer
// watches it over REST; then stored and analysed exactly as an upload of the
// same file is. Also: stopping a failing test early, and the access rule.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <google/protobuf/util/message_differencer.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <thread>

#include "insdiag/api/json.h"
#include "insdiag/v1/analyses.pb.h"
#include "insdiag/v1/live.pb.h"
#include "insdiag/v1/runs.pb.h"
#include "support/insdiagd_fixture.h"

// Last: httplib.h pulls in <resolv.h>, whose `_res` macro breaks Eigen.
#include <httplib.h>

namespace insdiag::testing {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;

// The step: five drift σ of the navigation-grade class's 30 µg accelerometer
// bias, on y, off the update grid.
constexpr double kStepOnsetS = 500.3;
constexpr char kStepFault[] = "acc_bias_step.y=1.471e-3@500.3";

// A TCP port on loopback nobody listens on now.
int UnusedPort() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address);
  socklen_t length = sizeof address;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
  ::close(fd);
  return ntohs(address.sin_port);
}

// Connects to 127.0.0.1:port, retrying while nobody listens yet.
int ConnectWithRetry(int port) {
  for (int attempt = 0; attempt < 100; ++attempt) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(static_cast<uint16_t>(port));
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0) return fd;
    ::close(fd);
    std::this_thread::sleep_for(100ms);
  }
  return -1;
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (!line.empty()) out.push_back(line);
  }
  return out;
}

class LiveTest : public ServerProcessTest {
 protected:
  void SetUp() override {
    DatabaseTest::SetUp();
    if (IsSkipped() || HasFatalFailure()) return;
    StartServer(INSDIAGD_PATH, "insdiag-live");
    if (HasFatalFailure()) return;
    auto simulated = RunToCompletion({"/usr/bin/python3", INSDIAG_BENCHSIM, "--out", (dir_ / "run.csv").string(),
                                      "--preset", "nav", "--profile", "positions", "--rate-hz", "10", "--duration",
                                      "900", "--seed", "7", "--fault", kStepFault, "--serial", "LIVE-E2E"},
                                     dir_, 120s);
    ASSERT_TRUE(simulated.ok() && simulated->exit_status == 0)
        << (simulated.ok() ? simulated->stderr_text : simulated.status().ToString());
  }
  std::vector<std::string> Cli(std::vector<std::string> args) const {
    args.insert(args.begin(), INSDIAG_CLI_PATH);
    for (const std::string& a : {std::string("--server"), address_}) args.push_back(a);
    return args;
  }

  // GET on the REST face with the admin token, parsed into `out`.
  void GetJson(const std::string& path, google::protobuf::Message& out) const {
    httplib::Client http("127.0.0.1", http_port_);
    auto got = http.Get(path, {{"Authorization", "Bearer " + token_}});
    ASSERT_TRUE(got) << path;
    ASSERT_EQ(got->status, 200) << path << ": " << got->body;
    ASSERT_TRUE(api::FromJson(got->body, &out).ok()) << got->body;
  }

  // The analysis once it has ended.
  v1::Analysis Finished(const std::string& name) const {
    v1::Analysis analysis;
    for (int i = 0; i < 600; ++i) {
      GetJson("/v1/" + name, analysis);
      if (analysis.state() != v1::Analysis::QUEUED && analysis.state() != v1::Analysis::RUNNING) break;
      std::this_thread::sleep_for(500ms);
    }
    return analysis;
  }
};

TEST_F(LiveTest, AStreamedTestShowsItsStepLiveAndIsStoredAndAnalysedAsItsUploadIs) {
  const int port = UnusedPort();
  auto stream = Subprocess::Start(Cli({"stream", "--listen", std::to_string(port), "--planned-duration", "900",
                                       "--json"}),
                                  dir_, {"INSDIAG_TOKEN=" + token_});
  ASSERT_TRUE(stream.ok()) << stream.status();
  const int bench = ConnectWithRetry(port);
  ASSERT_GE(bench, 0) << "insdiag stream does not listen on " << port;

  // The bench writes the file in ten parts; between them a viewer finds the
  // test among the live runs and starts watching it.
  const std::string text = ReadFile(dir_ / "run.csv");
  std::vector<std::string> watched;
  std::thread watcher;
  std::string live_name;
  for (int part = 0; part < 10; ++part) {
    const size_t from = text.size() * static_cast<size_t>(part) / 10;
    const size_t to = text.size() * static_cast<size_t>(part + 1) / 10;
    ASSERT_EQ(::write(bench, text.data() + from, to - from), static_cast<ssize_t>(to - from));
    std::this_thread::sleep_for(300ms);
    if (part == 2) {
      v1::ListLiveRunsResponse live;
      GetJson("/v1/liveRuns", live);
      for (const auto& run : live.live_runs()) {
        if (run.unit_serial() == "LIVE-E2E" && run.state() == v1::LiveRun::RECORDING) live_name = run.name();
      }
      ASSERT_FALSE(live_name.empty()) << "the test is not among the live runs";
      watcher = std::thread([&] {
        httplib::Client http("127.0.0.1", http_port_);
        http.set_read_timeout(120, 0);
        std::string body;
        http.Get("/v1/" + live_name + ":watch", {{"Authorization", "Bearer " + token_}},
                 [&](const char* data, size_t length) {
                   body.append(data, length);
                   return true;
                 });
        watched = Lines(body);
      });
    }
  }
  ::close(bench);
  const auto exit_status = stream->Wait(120s);
  if (watcher.joinable()) watcher.join();
  ASSERT_EQ(exit_status, std::optional<int>(0)) << stream->Stderr();

  // What the operator saw: the step shown within a minute of its onset.
  std::vector<v1::LiveRun> states;
  for (const std::string& line : Lines(stream->Stdout())) {
    ASSERT_TRUE(api::FromJson(line, &states.emplace_back()).ok()) << line;
  }
  ASSERT_GE(states.size(), 3u);
  double shown_at_s = -1.0;
  for (const v1::LiveRun& s : states) {
    for (const auto& f : s.fault_intervals()) {
      if (shown_at_s < 0.0 && f.end_s() >= kStepOnsetS) shown_at_s = s.time_s();
    }
  }
  ASSERT_GE(shown_at_s, 0.0) << "the step was never shown";
  EXPECT_LE(shown_at_s - kStepOnsetS, 60.0);
  for (const v1::LiveRun& s : states) {
    if (s.epoch_count() > 0 && s.time_s() < kStepOnsetS - 60.0) {
      EXPECT_EQ(s.verdict(), v1::AnalysisReport::GOOD) << s.time_s();
    }
  }
  const v1::LiveRun& last = states.back();
  ASSERT_EQ(last.state(), v1::LiveRun::STORED) << last.error().message();
  EXPECT_EQ(last.verdict(), v1::AnalysisReport::FAULTY);
  EXPECT_EQ(last.epoch_count(), last.planned_epoch_count());

  // What the viewer saw: the same test, in time order, to the same end.
  ASSERT_GE(watched.size(), 2u);
  v1::LiveRun watched_last;
  ASSERT_TRUE(api::FromJson(watched.back(), &watched_last).ok()) << watched.back();
  EXPECT_EQ(watched_last.name(), live_name);
  EXPECT_EQ(watched_last.state(), v1::LiveRun::STORED);
  EXPECT_EQ(watched_last.run(), last.run());
  EXPECT_EQ(watched_last.fault_intervals_size(), last.fault_intervals_size());

  // The stored run is the upload's, and so is its analysis.
  auto uploaded = RunToCompletion(Cli({"upload", (dir_ / "run.csv").string()}), dir_, 60s, {"INSDIAG_TOKEN=" + token_});
  ASSERT_TRUE(uploaded.ok() && uploaded->exit_status == 0) << uploaded->stderr_text;
  const std::string upload_name = Lines(uploaded->stdout_text).back();
  v1::Run streamed_run, uploaded_run;
  GetJson("/v1/" + last.run(), streamed_run);
  GetJson("/v1/" + upload_name, uploaded_run);
  EXPECT_EQ(streamed_run.sha256(), uploaded_run.sha256());
  EXPECT_EQ(streamed_run.sample_count(), uploaded_run.sample_count());
  // The same metadata but for each one's idempotency key.
  streamed_run.mutable_metadata()->clear_request_id();
  uploaded_run.mutable_metadata()->clear_request_id();
  EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(streamed_run.metadata(), uploaded_run.metadata()));

  httplib::Client http("127.0.0.1", http_port_);
  auto queued = http.Post("/v1/analyses", {{"Authorization", "Bearer " + token_}},
                          "{\"run\": \"" + upload_name + "\"}", "application/json");
  ASSERT_TRUE(queued && queued->status == 200) << (queued ? queued->body : "no answer");
  v1::Analysis upload_analysis;
  ASSERT_TRUE(api::FromJson(queued->body, &upload_analysis).ok());
  const v1::Analysis from_stream = Finished(last.analysis());
  const v1::Analysis from_upload = Finished(upload_analysis.name());
  ASSERT_EQ(from_stream.state(), v1::Analysis::SUCCEEDED) << from_stream.error().message();
  ASSERT_EQ(from_upload.state(), v1::Analysis::SUCCEEDED) << from_upload.error().message();
  google::protobuf::util::MessageDifferencer same;
  std::string differences;
  same.ReportDifferencesToString(&differences);
  EXPECT_TRUE(same.Compare(from_stream.report(), from_upload.report())) << differences;
}

TEST_F(LiveTest, AFailingTestStoppedEarlyKeepsWhatWasRecordedAndTheRoleIsChecked) {
  // The whole file at once on stdin: the monitor calls it FAULTY after the
  // step and the stream ends there; the stored run is what had been sent.
  auto stopped = RunToCompletion(Cli({"stream", (dir_ / "run.csv").string(), "--planned-duration", "900",
                                      "--stop-when-faulty"}),
                                 dir_, 120s, {"INSDIAG_TOKEN=" + token_});
  ASSERT_TRUE(stopped.ok());
  ASSERT_EQ(stopped->exit_status, 0) << stopped->stderr_text;
  EXPECT_THAT(stopped->stderr_text, HasSubstr("stopped at the first FAULTY verdict"));
  const std::vector<std::string> lines = Lines(stopped->stdout_text);
  ASSERT_GE(lines.size(), 2u);
  EXPECT_THAT(stopped->stdout_text, HasSubstr("verdict FAULTY"));
  const std::string stored_line = lines[lines.size() - 2];
  ASSERT_THAT(stored_line, ::testing::StartsWith("stored runs/")) << stopped->stdout_text;
  v1::Run run;
  GetJson("/v1/" + stored_line.substr(std::string("stored ").size()), run);
  EXPECT_GT(run.sample_count(), 10u * kStepOnsetS);
  EXPECT_LT(run.sample_count(), 10u * 900u);

  // Streaming writes: a viewer may watch but not feed a test; no token, no entry.
  auto created = RunToCompletion(Cli({"tokens", "create", "--name", "wall-display", "--role", "viewer"}), dir_, 30s,
                                 {"INSDIAG_TOKEN=" + token_});
  ASSERT_TRUE(created.ok() && created->exit_status == 0);
  std::smatch made;
  ASSERT_TRUE(std::regex_search(created->stdout_text, made, std::regex(R"(\n(insdiag_[A-Za-z0-9_-]+)\n)")));
  auto as_viewer = RunToCompletion(Cli({"stream", (dir_ / "run.csv").string()}), dir_, 30s,
                                   {"INSDIAG_TOKEN=" + made[1].str()});
  ASSERT_TRUE(as_viewer.ok());
  EXPECT_EQ(as_viewer->exit_status, 1);
  EXPECT_THAT(as_viewer->stderr_text, HasSubstr("PERMISSION_DENIED"));
  auto anonymous = RunToCompletion(Cli({"stream", (dir_ / "run.csv").string()}), dir_, 30s, {"INSDIAG_TOKEN="});
  ASSERT_TRUE(anonymous.ok());
  EXPECT_EQ(anonymous->exit_status, 1);
  EXPECT_THAT(anonymous->stderr_text, HasSubstr("UNAUTHENTICATED"));

  // The write is audited with who streamed it.
  httplib::Client http("127.0.0.1", http_port_);
  auto audit = http.Get("/v1/auditEvents", {{"Authorization", "Bearer " + token_}});
  ASSERT_TRUE(audit && audit->status == 200);
  EXPECT_THAT(audit->body, HasSubstr("insdiag.v1.LiveRunService.MonitorRun"));
  EXPECT_THAT(audit->body, HasSubstr(run.name()));
}

TEST_F(LiveTest, AFileStillBeingWrittenIsFollowedUntilItHasBeenIdle) {
  // The DAQ has written the first half when the operator starts the stream;
  // the rest comes a second later; then the file stays as it is.
  const std::string text = ReadFile(dir_ / "run.csv");
  const std::filesystem::path growing = dir_ / "growing.csv";
  const size_t half = text.find('\n', text.size() / 2) + 1;
  { std::ofstream(growing, std::ios::binary) << text.substr(0, half); }
  auto stream = Subprocess::Start(Cli({"stream", growing.string(), "--follow", "--idle-timeout", "2",
                                       "--planned-duration", "900"}),
                                  dir_, {"INSDIAG_TOKEN=" + token_});
  ASSERT_TRUE(stream.ok()) << stream.status();
  std::this_thread::sleep_for(1s);
  { std::ofstream(growing, std::ios::binary | std::ios::app) << text.substr(half); }
  const auto exit_status = stream->Wait(60s);
  ASSERT_EQ(exit_status, std::optional<int>(0)) << stream->Stderr();
  const std::vector<std::string> lines = Lines(stream->Stdout());
  ASSERT_GE(lines.size(), 2u);
  const std::string stored_line = lines[lines.size() - 2];
  ASSERT_THAT(stored_line, ::testing::StartsWith("stored runs/")) << stream->Stdout();
  v1::Run run;
  GetJson("/v1/" + stored_line.substr(std::string("stored ").size()), run);
  EXPECT_EQ(run.sample_count(), 10u * 900u);
}

}  // namespace
}  // namespace insdiag::testing
