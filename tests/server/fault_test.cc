// Faults that must lose nothing acknowledged and leave nothing half-done,
// with the real insdiagd on a real PostgreSQL: the server killed with
// SIGKILL in the middle of an upload stream, a client that goes away
// mid-stream, and a deadline that expires.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <fstream>
#include <regex>
#include <thread>

#include "insdiag/api/run_codec.h"
#include "insdiag/kb/pg.h"
#include "server_fixture.h"
#include "support/subprocess.h"
#include "support/synthetic_run.h"

namespace insdiag::testing {
namespace {

using namespace std::chrono_literals;

class FaultTest : public DatabaseTest {
 protected:
  void SetUp() override {
    DatabaseTest::SetUp();
    if (IsSkipped() || HasFatalFailure()) return;
    dir_ = MakeTempDir("insdiag-fault");
  }
  void TearDown() override {
    std::filesystem::remove_all(dir_);
    DatabaseTest::TearDown();
  }

  // insdiagd on the test database; its gRPC address and the first admin token.
  Subprocess StartServer(const std::string& tag, std::string* address, std::string* token) {
    std::filesystem::create_directories(dir_ / tag);
    auto process = Subprocess::Start({INSDIAGD_PATH, "--database-url", database_url(), "--data-dir",
                                      (dir_ / "data").string(), "--grpc-port", "0", "--http-port", "0",
                                      "--workers", "0", "--fleet-refresh-seconds", "0"},
                                     dir_ / tag);
    EXPECT_TRUE(process.ok()) << process.status();
    const std::regex listening(R"(listening grpc=[^ ]*:(\d+))");
    for (int i = 0; i < 600 && address->empty(); ++i) {
      std::smatch match;
      const std::string out = process->Stdout();
      if (std::regex_search(out, match, listening)) *address = "127.0.0.1:" + match[1].str();
      std::this_thread::sleep_for(25ms);
    }
    std::ifstream(dir_ / "data" / "admin-token") >> *token;
    return std::move(*process);
  }

  // Rows of the run tables: nothing of a run may be there without the run.
  std::string StoredRows() {
    auto db = kb::Connection::Open(database_url());
    EXPECT_TRUE(db.ok());
    auto rows = db->Exec(
        "SELECT (SELECT count(*) FROM runs) || ' runs, ' || (SELECT count(*) FROM run_sample_chunks) || ' chunks, ' "
        "|| (SELECT count(*) FROM units) || ' units'");
    EXPECT_TRUE(rows.ok()) << rows.status();
    return rows.ok() ? rows->String(0, 0) : "";
  }

  std::filesystem::path dir_;
};

// Streams `run` and calls `midway` once half its messages are written;
// returns the call's status.
grpc::Status UploadWith(v1::RunService::Stub& stub, const engine::BenchRun& run, const std::string& request_id,
                        grpc::ClientContext& context, const std::function<void()>& midway) {
  v1::Run response;
  auto stream = stub.UploadRun(&context, &response);
  std::vector<v1::UploadRunRequest> messages;
  api::ForEachUploadRequest(run, request_id, 2'000, [&](const v1::UploadRunRequest& m) {
    messages.push_back(m);
    return true;
  });
  for (std::size_t i = 0; i < messages.size(); ++i) {
    if (i == messages.size() / 2 && midway) midway();
    if (!stream->Write(messages[i])) break;
  }
  stream->WritesDone();
  return stream->Finish();
}

TEST_F(FaultTest, AServerKilledMidUploadStoresNothingAndTheRetryStoresTheRunOnce) {
  const engine::BenchRun run = SyntheticStaticRun(60'000, 50.0, 21);
  std::string address, token;
  auto first = StartServer("first", &address, &token);
  ASSERT_FALSE(address.empty()) << first.Stderr();
  {
    auto stub = v1::RunService::NewStub(client::Connect(address, token));
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + 60s);
    const grpc::Status killed = UploadWith(*stub, run, "retry-me", context, [&] {
      first.Signal(SIGKILL);
      first.Wait(10s);
    });
    EXPECT_FALSE(killed.ok()) << "an upload whose server died was acknowledged";
  }
  EXPECT_EQ(StoredRows(), "0 runs, 0 chunks, 0 units") << "a killed upload left part of itself";

  std::string second_address, second_token;
  auto second = StartServer("second", &second_address, &second_token);
  ASSERT_FALSE(second_address.empty()) << second.Stderr();
  EXPECT_EQ(second_token, token) << "a later start made another first token";
  auto stub = v1::RunService::NewStub(client::Connect(second_address, token));
  client::UploadOptions options;
  options.request_id = "retry-me";
  auto stored = client::UploadRun(*stub, run, options);
  ASSERT_TRUE(stored.ok()) << stored.status();
  auto again = client::UploadRun(*stub, run, options);
  ASSERT_TRUE(again.ok()) << again.status();
  EXPECT_EQ(again->name(), stored->name()) << "the retried request id stored a second run";
  EXPECT_THAT(StoredRows(), ::testing::MatchesRegex("1 runs, [1-9][0-9]* chunks, 1 units"));
  second.Signal(SIGTERM);
  second.Wait(20s);
}

TEST_F(FaultTest, AClientThatGoesAwayOrADeadlineThatExpiresMidUploadStoresNothing) {
  const engine::BenchRun run = SyntheticStaticRun(60'000, 50.0, 22);
  std::string address, token;
  auto server = StartServer("server", &address, &token);
  ASSERT_FALSE(address.empty()) << server.Stderr();
  auto stub = v1::RunService::NewStub(client::Connect(address, token));
  {
    grpc::ClientContext context;
    const grpc::Status cancelled = UploadWith(*stub, run, "", context, [&] { context.TryCancel(); });
    EXPECT_EQ(cancelled.error_code(), grpc::StatusCode::CANCELLED);
  }
  {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + 2s);
    const grpc::Status expired = UploadWith(*stub, run, "", context, [] { std::this_thread::sleep_for(3s); });
    EXPECT_EQ(expired.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED);
  }
  // The server finishes what it was doing with the broken streams.
  std::this_thread::sleep_for(1s);
  EXPECT_EQ(StoredRows(), "0 runs, 0 chunks, 0 units");
  // And is well: the same run uploads whole.
  auto stored = client::UploadRun(*stub, run, client::UploadOptions{});
  EXPECT_TRUE(stored.ok()) << stored.status();
  server.Signal(SIGTERM);
  server.Wait(20s);
}

}  // namespace
}  // namespace insdiag::testing
