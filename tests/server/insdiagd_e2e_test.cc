// The real programs: insdiagd with its embedded PostgreSQL in a temporary
// data directory, and the insdiag CLI uploading to it.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <grpcpp/generic/generic_stub.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <iostream>
#include <map>
#include <fstream>
#include <future>
#include <regex>
#include <sstream>
#include <thread>

#include "insdiag/benchrun/bench_run_csv.h"
#include "insdiag/client/run_client.h"
#include "insdiag/v1/runs.grpc.pb.h"
#include "support/poll.h"
#include "support/subprocess.h"
#include "support/synthetic_run.h"

// Last: httplib.h pulls in <resolv.h>, whose `_res` macro breaks Eigen.
#include <httplib.h>

namespace insdiag::testing {
namespace {

using ::testing::HasSubstr;
using namespace std::chrono_literals;

struct Ports {
  int grpc = 0;
  int http = 0;
};

// Waits for insdiagd's "listening grpc=…:N http=…:M" line.
std::optional<Ports> AwaitListening(Subprocess& server, std::chrono::seconds timeout) {
  const std::regex listening(R"(listening grpc=[^ ]*:(\d+) http=[^ ]*:(\d+))");
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    std::smatch match;
    const std::string out = server.Stdout();
    if (std::regex_search(out, match, listening)) return Ports{std::stoi(match[1]), std::stoi(match[2])};
    if (server.Wait(0ms)) return std::nullopt;
    std::this_thread::sleep_for(50ms);
  }
  return std::nullopt;
}

// grpc.health.v1.Health/Check for the whole server; true when SERVING
// (response bytes 08 01: no C++ code is generated from health.proto here).
bool GrpcHealthy(int port) {
  grpc::GenericStub stub(client::Connect("127.0.0.1:" + std::to_string(port), /*token=*/""));
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + 5s);
  grpc::Slice empty(std::string{});
  const grpc::ByteBuffer request(&empty, 1);
  grpc::ByteBuffer response;
  std::promise<grpc::Status> done;
  stub.UnaryCall(&context, "/grpc.health.v1.Health/Check", grpc::StubOptions(), &request, &response,
                 [&done](grpc::Status status) { done.set_value(std::move(status)); });
  if (!done.get_future().get().ok()) return false;
  std::vector<grpc::Slice> slices;
  response.Dump(&slices);
  std::string bytes;
  for (const auto& slice : slices) bytes.append(reinterpret_cast<const char*>(slice.begin()), slice.size());
  return bytes == std::string("\x08\x01", 2);
}

// Asks grpc.reflection.v1alpha.ServerReflection to list the services and
// returns the raw response bytes (service names appear in them verbatim).
// The request is ServerReflectionRequest{list_services = ""}: field 7, an
// empty string, on the wire 3a 00.
std::string ReflectionListing(int port) {
  class Listing final : public grpc::ClientBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer> {
   public:
    Listing() : request_slice_(std::string("\x3a\x00", 2)), request_(&request_slice_, 1) {}
    void Begin(grpc::GenericStub& stub, grpc::ClientContext& context) {
      stub.PrepareBidiStreamingCall(&context, "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo",
                                    grpc::StubOptions(), this);
      StartWrite(&request_);
      StartRead(&response_);
      StartCall();
    }
    void OnWriteDone(bool) override { StartWritesDone(); }
    void OnReadDone(bool ok) override {
      if (!ok) return;
      std::vector<grpc::Slice> slices;
      response_.Dump(&slices);
      for (const auto& slice : slices) bytes_.append(reinterpret_cast<const char*>(slice.begin()), slice.size());
      StartRead(&response_);
    }
    void OnDone(const grpc::Status&) override { done_.set_value(bytes_); }
    std::future<std::string> Result() { return done_.get_future(); }

   private:
    grpc::Slice request_slice_;
    grpc::ByteBuffer request_;
    grpc::ByteBuffer response_;
    std::string bytes_;
    std::promise<std::string> done_;
  };
  grpc::GenericStub stub(client::Connect("127.0.0.1:" + std::to_string(port), /*token=*/""));
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + 5s);
  Listing listing;
  auto result = listing.Result();
  listing.Begin(stub, context);
  return result.get();
}

// Running, not merely a zombie waiting for a reaper (pg_ctl leaves the
// postmaster to whoever adopts orphans, which may be slow to reap it).
bool ProcessAlive(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string text;
  if (!std::getline(stat, text)) return false;
  const auto after_name = text.rfind(')');
  return after_name != std::string::npos && after_name + 2 < text.size() && text[after_name + 2] != 'Z';
}

class InsdiagdTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = MakeTempDir("insdiagd-e2e");
    ASSERT_FALSE(dir_.empty());
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  Subprocess StartServer(const std::vector<std::string>& extra = {}) {
    std::vector<std::string> argv = {INSDIAGD_PATH, "--data-dir", (dir_ / "data").string(), "--grpc-port", "0",
                                     "--http-port", "0", "--bind", "127.0.0.1"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    auto server = Subprocess::Start(argv, dir_);
    EXPECT_TRUE(server.ok()) << server.status();
    return std::move(*server);
  }

  std::filesystem::path dir_;
};

TEST_F(InsdiagdTest, ServesHealthAcceptsCliUploadAndStopsWithPostgresOnSigterm) {
  auto server = StartServer();
  const auto ports = AwaitListening(server, 60s);
  ASSERT_TRUE(ports) << "insdiagd did not come up:\n" << server.Stderr();
  EXPECT_TRUE(GrpcHealthy(ports->grpc));
  EXPECT_THAT(ReflectionListing(ports->grpc), HasSubstr("insdiag.v1.RunService")) << "reflection is off";
  httplib::Client http("127.0.0.1", ports->http);
  auto health = http.Get("/healthz");
  ASSERT_TRUE(health);
  EXPECT_EQ(health->status, 200);

  // The first start wrote an admin token only its user can read, and said where.
  const auto token_file = dir_ / "data" / "admin-token";
  ASSERT_TRUE(std::filesystem::exists(token_file)) << server.Stderr();
  EXPECT_EQ(std::filesystem::status(token_file).permissions() & std::filesystem::perms::all,
            std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);
  EXPECT_THAT(server.Stderr(), HasSubstr(token_file.string()));
  std::string admin_token;
  std::ifstream(token_file) >> admin_token;
  http.set_bearer_token_auth(admin_token.c_str());

  const auto file = dir_ / "run.csv";
  ASSERT_TRUE(benchrun::WriteBenchRunFile(SyntheticStaticRun(180'000, 50.0, 11), file).ok());
  const std::string grpc_address = "127.0.0.1:" + std::to_string(ports->grpc);
  auto anonymous = RunToCompletion({INSDIAG_CLI_PATH, "upload", file.string(), "--server", grpc_address}, dir_, 60s);
  ASSERT_TRUE(anonymous.ok());
  EXPECT_EQ(anonymous->exit_status, 1);
  EXPECT_THAT(anonymous->stderr_text, HasSubstr("UNAUTHENTICATED"));
  // How fast uploads go is measured by the benchmarks (docs/PERFORMANCE.md); here, that one is stored whole.
  auto upload = RunToCompletion({INSDIAG_CLI_PATH, "upload", file.string(), "--server", grpc_address, "--token",
                                 admin_token},
                                dir_, 60s);
  ASSERT_TRUE(upload.ok()) << upload.status();
  EXPECT_EQ(upload->exit_status, 0) << upload->stderr_text;
  std::smatch name;
  ASSERT_TRUE(std::regex_match(upload->stdout_text, name, std::regex(R"((runs/[0-9a-f-]{36})\n)")))
      << upload->stdout_text;
  auto got = http.Get(("/v1/" + name[1].str()).c_str());
  ASSERT_TRUE(got);
  EXPECT_THAT(got->body, HasSubstr(R"("sampleCount":"180000")"));

  // The PostgreSQL the server started, by its postmaster.pid.
  std::ifstream pid_file(dir_ / "data" / "pg" / "postmaster.pid");
  pid_t postmaster = 0;
  ASSERT_TRUE(pid_file >> postmaster) << "no postmaster.pid: the embedded PostgreSQL is not running";
  ASSERT_TRUE(ProcessAlive(postmaster));

  server.Signal(SIGTERM);
  const auto exit_status = server.Wait(60s);
  ASSERT_TRUE(exit_status) << "insdiagd did not stop on SIGTERM";
  EXPECT_EQ(*exit_status, 0) << server.Stderr();
  EXPECT_FALSE(std::filesystem::exists(dir_ / "data" / "pg" / "postmaster.pid"));
  EXPECT_FALSE(ProcessAlive(postmaster)) << "PostgreSQL outlived the server";
}

// No PostgreSQL outlives its server, however the server ends: killed, or
// aborted (SIGABRT, as an assertion does), or stopped. The guard stops the
// postmaster; each restart on the same data directory serves every run
// stored before.
TEST_F(InsdiagdTest, KilledOrAbortedItsPostgresStopsTooAndARestartServesTheSameRuns) {
  std::vector<std::string> stored_names;
  for (const int signal : {SIGKILL, SIGABRT, SIGTERM}) {
    auto server = StartServer();
    const auto ports = AwaitListening(server, 60s);
    ASSERT_TRUE(ports) << "insdiagd did not take the data directory over:\n" << server.Stderr();
    std::string admin_token;
    std::ifstream(dir_ / "data" / "admin-token") >> admin_token;
    httplib::Client http("127.0.0.1", ports->http);
    http.set_bearer_token_auth(admin_token.c_str());
    for (const std::string& name : stored_names) {
      auto kept = http.Get(("/v1/" + name).c_str());
      ASSERT_TRUE(kept);
      EXPECT_EQ(kept->status, 200) << name << " was lost across the restart";
    }
    auto upload = http.Post("/v1/runs:upload", benchrun::FormatBenchRun(SyntheticStaticRun(2'000, 50.0, signal)),
                            "text/csv");
    ASSERT_TRUE(upload);
    ASSERT_EQ(upload->status, 200) << upload->body;
    std::smatch name;
    ASSERT_TRUE(std::regex_search(upload->body, name, std::regex(R"((runs/[0-9a-f-]{36}))")));
    stored_names.push_back(name[1]);

    std::ifstream pid_file(dir_ / "data" / "pg" / "postmaster.pid");
    pid_t postmaster = 0;
    ASSERT_TRUE(pid_file >> postmaster);
    server.Signal(signal);
    ASSERT_TRUE(server.Wait(60s)) << "insdiagd did not end on signal " << signal;
    EXPECT_TRUE(PollUntil([&] { return !ProcessAlive(postmaster); }, 30s))
        << "PostgreSQL outlived insdiagd ended by signal " << signal;
  }
}

// One server per data directory: a second is refused, saying why, and the
// first serves on.
TEST_F(InsdiagdTest, ASecondServerOnTheSameDataDirectoryIsRefused) {
  auto first = StartServer();
  const auto ports = AwaitListening(first, 60s);
  ASSERT_TRUE(ports) << "insdiagd did not come up:\n" << first.Stderr();
  auto second = StartServer();
  const auto exit_status = second.Wait(60s);
  ASSERT_TRUE(exit_status) << "the second insdiagd kept running";
  EXPECT_NE(*exit_status, 0);
  EXPECT_THAT(second.Stderr(), HasSubstr("another insdiagd serves the data directory"));
  EXPECT_TRUE(GrpcHealthy(ports->grpc));
  first.Signal(SIGTERM);
  EXPECT_TRUE(first.Wait(60s));
}

// A page left open on a queued analysis holds a watch that no worker will
// end once the server stops: SIGTERM must end the watch, not wait for it.
TEST_F(InsdiagdTest, StopsOnSigtermWhileAWatchWaitsOnAnAnalysisNoWorkerWillRun) {
  auto server = StartServer({"--workers", "0"});
  const auto ports = AwaitListening(server, 60s);
  ASSERT_TRUE(ports) << "insdiagd did not come up:\n" << server.Stderr();
  std::string admin_token;
  std::ifstream(dir_ / "data" / "admin-token") >> admin_token;
  const auto file = dir_ / "run.csv";
  ASSERT_TRUE(benchrun::WriteBenchRunFile(SyntheticStaticRun(6'000, 10.0, 3), file).ok());
  auto upload = RunToCompletion({INSDIAG_CLI_PATH, "upload", file.string(), "--server",
                                 "127.0.0.1:" + std::to_string(ports->grpc), "--token", admin_token},
                                dir_, 60s);
  ASSERT_TRUE(upload.ok() && upload->exit_status == 0);
  httplib::Client http("127.0.0.1", ports->http);
  http.set_bearer_token_auth(admin_token.c_str());
  const std::string run = upload->stdout_text.substr(0, upload->stdout_text.find('\n'));
  auto queued = http.Post("/v1/analyses", "{\"run\": \"" + run + "\"}", "application/json");
  ASSERT_TRUE(queued && queued->status == 200) << (queued ? queued->body : "no answer");
  std::smatch analysis;
  ASSERT_TRUE(std::regex_search(queued->body, analysis, std::regex(R"(analyses/[0-9a-f-]{36})")));

  std::string watched;
  std::atomic<bool> first_message{false};
  std::thread watcher([&, name = analysis.str()] {
    httplib::Client watch("127.0.0.1", ports->http);
    watch.set_bearer_token_auth(admin_token.c_str());
    watch.set_read_timeout(60, 0);
    watch.Get(("/v1/" + name + ":watch").c_str(), [&](const char* data, size_t length) {
      watched.append(data, length);
      first_message = true;
      return true;
    });
  });
  // The watch is open and has its first message.
  EXPECT_TRUE(testing::PollUntil([&] { return first_message.load(); }, 30s)) << "the watch sent nothing";
  server.Signal(SIGTERM);
  const auto exit_status = server.Wait(30s);
  watcher.join();
  ASSERT_TRUE(exit_status) << "insdiagd did not stop on SIGTERM while a watch was open";
  EXPECT_EQ(*exit_status, 0) << server.Stderr();
  EXPECT_THAT(watched, HasSubstr("QUEUED"));
  EXPECT_THAT(watched, HasSubstr("the server is stopping; watch again"));
}

TEST_F(InsdiagdTest, CliRefusesABadFileNamingLineAndColumnAndMisuseWithStatus2) {
  const auto file = dir_ / "bad.csv";
  std::string csv = benchrun::FormatBenchRun(SyntheticStaticRun(100, 50.0, 1));
  const auto header = csv.find("\nt,");
  const auto row = csv.find('\n', header + 1);  // end of the header line
  csv = csv.substr(0, row + 1) + "x" + csv.substr(row + 1);  // first data row: t = "x0.02"
  std::ofstream(file) << csv;
  const int line = static_cast<int>(std::count(csv.begin(), csv.begin() + static_cast<std::ptrdiff_t>(row), '\n')) + 2;

  // No server needed: the file is refused before anything is sent.
  auto refused = RunToCompletion({INSDIAG_CLI_PATH, "upload", file.string(), "--server", "127.0.0.1:1"}, dir_, 30s);
  ASSERT_TRUE(refused.ok());
  EXPECT_EQ(refused->exit_status, 1);
  EXPECT_THAT(refused->stderr_text, HasSubstr(file.string() + ":" + std::to_string(line) + ":1"));
  EXPECT_TRUE(refused->stdout_text.empty());

  auto misuse = RunToCompletion({INSDIAG_CLI_PATH, "upload"}, dir_, 30s);
  ASSERT_TRUE(misuse.ok());
  EXPECT_EQ(misuse->exit_status, 2);
}

TEST_F(InsdiagdTest, RefusesToStartWhenAnAppliedMigrationChanged) {
  const auto migrations = dir_ / "migrations";
  std::filesystem::copy(INSDIAG_SOURCE_DIR "/migrations", migrations);
  {
    auto server = StartServer({"--migrations-dir", migrations.string()});
    ASSERT_TRUE(AwaitListening(server, 60s)) << server.Stderr();
    server.Signal(SIGTERM);
    ASSERT_EQ(server.Wait(60s), 0);
  }
  std::ofstream(migrations / "0001_runs.sql", std::ios::app) << "\n-- edited after it was applied\n";
  auto server = StartServer({"--migrations-dir", migrations.string()});
  const auto exit_status = server.Wait(60s);
  ASSERT_TRUE(exit_status) << "insdiagd started on a changed migration";
  EXPECT_EQ(*exit_status, 1);
  EXPECT_THAT(server.Stderr(), HasSubstr("0001_runs.sql has changed"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "data" / "pg" / "postmaster.pid")) << "PostgreSQL left running";
}

// PostgreSQL restarted under a stream of uploads: requests in flight fail
// cleanly (UNAVAILABLE, nothing stored), the server reconnects by itself,
// and every upload it acknowledged is there afterwards.
TEST_F(InsdiagdTest, APostgresRestartUnderLoadLosesNothingAcknowledgedAndTheServerReconnects) {
  auto server = StartServer({"--workers", "0"});
  const auto ports = AwaitListening(server, 60s);
  ASSERT_TRUE(ports) << "insdiagd did not come up:\n" << server.Stderr();
  std::string token;
  std::ifstream(dir_ / "data" / "admin-token") >> token;
  auto stub = v1::RunService::NewStub(client::Connect("127.0.0.1:" + std::to_string(ports->grpc), token));

  std::atomic<bool> stop{false}, restarted{false};
  std::vector<std::pair<std::string, std::int64_t>> acknowledged;  // run, samples
  std::map<absl::StatusCode, int> refused;
  std::map<absl::StatusCode, std::string> refusal;  // a message of each code
  std::atomic<int> acknowledged_count{0}, acknowledged_after_restart{0};
  std::thread load([&] {
    for (std::uint32_t seed = 1; !stop; ++seed) {
      client::UploadOptions options;
      options.request_id = client::NewRequestId();
      options.deadline = 20s;
      const bool after = restarted;
      auto run = client::UploadRun(*stub, SyntheticStaticRun(500 + seed % 7, 50.0, seed), options);
      if (run.ok()) {
        acknowledged.emplace_back(run->name(), run->sample_count());
        ++acknowledged_count;
        acknowledged_after_restart += after ? 1 : 0;
      } else {
        ++refused[run.status().code()];
        refusal[run.status().code()] = std::string(run.status().message());
      }
    }
  });
  // The load runs before the restart.
  EXPECT_TRUE(testing::PollUntil([&] { return acknowledged_count >= 3; }, 60s)) << server.Stderr();
  std::vector<std::string> pg_ctl = {"/usr/lib/postgresql/15/bin/pg_ctl", "restart", "-w", "-t", "60", "-m", "fast",
                                     "-D", (dir_ / "data" / "pg").string(), "-l",
                                     (dir_ / "data" / "run" / "postgresql.log").string()};
  if (::geteuid() == 0) pg_ctl.insert(pg_ctl.begin(), {"/usr/sbin/runuser", "-u", "postgres", "--"});
  auto restart = RunToCompletion(pg_ctl, dir_, 90s);
  restarted = true;
  // The load goes on until the server has acknowledged uploads on the restarted database.
  testing::PollUntil([&] { return acknowledged_after_restart >= 3; }, 60s);
  stop = true;
  load.join();
  ASSERT_TRUE(restart.ok() && restart->exit_status == 0) << (restart.ok() ? restart->stderr_text : "");

  EXPECT_FALSE(server.Wait(0ms).has_value()) << "insdiagd died with its database:\n" << server.Stderr();
  EXPECT_GT(acknowledged_after_restart.load(), 0) << "the server did not reconnect";
  for (const auto& [code, count] : refused) {
    EXPECT_EQ(code, absl::StatusCode::kUnavailable) << count << " uploads refused with " << absl::StatusCodeToString(code)
                                                    << ", e.g. " << refusal[code];
  }
  for (const auto& [name, samples] : acknowledged) {
    grpc::ClientContext context;
    v1::GetRunRequest request;
    request.set_name(name);
    v1::Run stored;
    const grpc::Status got = stub->GetRun(&context, request, &stored);
    ASSERT_TRUE(got.ok()) << name << ": " << got.error_message();
    EXPECT_EQ(stored.sample_count(), samples) << name;
  }
  int refused_total = 0;
  for (const auto& [code, count] : refused) refused_total += count;
  std::cout << "uploads acknowledged " << acknowledged.size() << " (after the restart " << acknowledged_after_restart
            << "), refused " << refused_total << "\n";
  server.Signal(SIGTERM);
  server.Wait(60s);
}

// A server whose database is down says so in its health (gRPC and
// /healthz), and says SERVING again once the database is back.
TEST_F(InsdiagdTest, HealthSaysNotServingWhileTheDatabaseIsDownAndTheSupervisorStartsItAgain) {
  auto server = StartServer({"--workers", "0"});
  const auto ports = AwaitListening(server, 60s);
  ASSERT_TRUE(ports) << "insdiagd did not come up:\n" << server.Stderr();
  httplib::Client http("127.0.0.1", ports->http);
  const auto health_becomes = [&](int status, std::chrono::milliseconds within) {
    return testing::PollUntil(
        [&] {
          auto answer = http.Get("/healthz");
          return answer && answer->status == status;
        },
        within, 100ms);
  };
  ASSERT_TRUE(health_becomes(200, 10s));
  const auto pg_ctl = [&](std::vector<std::string> args) {
    args.insert(args.begin(), "/usr/lib/postgresql/15/bin/pg_ctl");
    if (::geteuid() == 0) args.insert(args.begin(), {"/usr/sbin/runuser", "-u", "postgres", "--"});
    auto done = RunToCompletion(args, dir_, 90s);
    return done.ok() && done->exit_status == 0;
  };
  const std::string cluster = (dir_ / "data" / "pg").string();
  // An immediate stop, as a crash or a shutdown for want of disk space leaves it.
  ASSERT_TRUE(pg_ctl({"stop", "-w", "-m", "immediate", "-D", cluster}));
  EXPECT_TRUE(health_becomes(503, 10s)) << "the database is down and /healthz still says SERVING";
  // The supervisor looks every 5 s and starts the cluster found stopped twice; the server reconnects.
  EXPECT_TRUE(health_becomes(200, 30s)) << "the embedded database was not started again:\n" << server.Stderr();
  EXPECT_TRUE(GrpcHealthy(ports->grpc));
  // The server reconnects as soon as PostgreSQL accepts connections, which
  // can be before the supervisor's pg_ctl returns and it says so.
  const auto stderr_says = [&](std::string_view text, std::chrono::milliseconds within) {
    return testing::PollUntil([&] { return server.Stderr().find(text) != std::string::npos; }, within, 100ms);
  };
  EXPECT_TRUE(stderr_says("the embedded PostgreSQL runs again", 30s)) << server.Stderr();
  EXPECT_TRUE(pg_ctl({"status", "-D", cluster}));
  server.Signal(SIGTERM);
  EXPECT_EQ(server.Wait(60s), 0);
  EXPECT_FALSE(pg_ctl({"status", "-D", cluster})) << "insdiagd stopped, and its PostgreSQL still runs";
}

// With --log-format json every line insdiagd writes to stderr is one JSON
// object with its time, level and message, for a log collector: the first
// start's token notice and the shutdown among them.
TEST_F(InsdiagdTest, LogsOneJsonObjectALineOnRequest) {
  auto server = StartServer({"--workers", "0", "--log-format", "json"});
  const auto ports = AwaitListening(server, 60s);
  ASSERT_TRUE(ports) << "insdiagd did not come up:\n" << server.Stderr();
  server.Signal(SIGTERM);
  ASSERT_EQ(server.Wait(60s), 0) << server.Stderr();
  std::istringstream lines(server.Stderr());
  std::vector<std::string> messages;
  for (std::string line; std::getline(lines, line);) {
    google::protobuf::Struct entry;
    ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(line, &entry).ok()) << "not a JSON object: " << line;
    const auto& fields = entry.fields();
    ASSERT_TRUE(fields.contains("time") && fields.contains("level") && fields.contains("message")) << line;
    EXPECT_THAT(fields.at("time").string_value(), ::testing::MatchesRegex(R"([0-9]{4}-[0-9]{2}-[0-9]{2}T[0-9]{2}:[0-9]{2}:[0-9]{2}\.[0-9]{3}Z)"));
    EXPECT_THAT(fields.at("level").string_value(), ::testing::AnyOf("info", "warning", "error"));
    messages.push_back(fields.at("message").string_value());
  }
  EXPECT_THAT(messages, ::testing::Contains(HasSubstr("an admin token is in")));
  EXPECT_THAT(messages, ::testing::Contains(HasSubstr("SIGTERM, shutting down")));
}

}  // namespace
}  // namespace insdiag::testing
