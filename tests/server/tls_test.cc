// TLS for both faces, through real clients: a gRPC channel and an HTTPS
// client that verify the server against a CA file get in; plaintext clients
// and clients that trust another CA do not; the CLI and the Python client
// take a CA file.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "insdiag/client/unary.h"
#include "insdiag/v1/access.grpc.pb.h"
#include "server_fixture.h"
#include "support/subprocess.h"

namespace insdiag::testing {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;

std::string ReadFile(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// A self-signed certificate for localhost and 127.0.0.1, made by openssl.
bool MakeCertificate(const std::filesystem::path& dir, const std::string& name) {
  auto made = RunToCompletion({"/usr/bin/openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "1", "-subj",
                               "/CN=localhost", "-addext", "subjectAltName=DNS:localhost,IP:127.0.0.1", "-keyout",
                               (dir / (name + ".key")).string(), "-out", (dir / (name + ".pem")).string()},
                              dir, 60s);
  return made.ok() && made->exit_status == 0;
}

class TlsTest : public DatabaseTest {
 protected:
  void SetUp() override {
    DatabaseTest::SetUp();
    if (IsSkipped() || HasFatalFailure()) return;
    dir_ = MakeTempDir("insdiag-tls");
    ASSERT_TRUE(MakeCertificate(dir_, "server")) << "openssl could not make a certificate";
    ASSERT_TRUE(MakeCertificate(dir_, "stranger"));
    server::InsdiagServer::Options options;
    options.grpc_port = 0;
    options.http_port = 0;
    options.workers.workers = 1;  // the Python client's analysis
    options.tls_cert_file = (dir_ / "server.pem").string();
    options.tls_key_file = (dir_ / "server.key").string();
    auto started = server::InsdiagServer::Start(pool(), options);
    ASSERT_TRUE(started.ok()) << started.status();
    server_ = std::move(*started);
    token_ = MakeToken(pool(), v1::VIEWER, "tls reader");
  }
  void TearDown() override {
    if (server_) server_->Shutdown();
    server_.reset();
    std::filesystem::remove_all(dir_);
    DatabaseTest::TearDown();
  }

  absl::StatusOr<v1::Caller> CallerOver(const std::string& ca_pem) {
    auto stub = v1::AccessService::NewStub(
        client::Connect("localhost:" + std::to_string(server_->grpc_port()), token_, ca_pem));
    return client::CallUnary<v1::Caller>(
        [&](grpc::ClientContext* c, v1::Caller* r) { return stub->GetCaller(c, v1::GetCallerRequest(), r); },
        std::chrono::seconds(10));
  }

  std::filesystem::path dir_;
  std::unique_ptr<server::InsdiagServer> server_;
  std::string token_;
};

TEST_F(TlsTest, GrpcVerifiesTheServerAgainstTheCaFileAndRefusesPlaintextAndStrangers) {
  auto verified = CallerOver(ReadFile(dir_ / "server.pem"));
  ASSERT_TRUE(verified.ok()) << verified.status();
  EXPECT_EQ(verified->display_name(), "tls reader");
  EXPECT_EQ(CallerOver("").status().code(), absl::StatusCode::kUnavailable) << "a plaintext client got in";
  EXPECT_EQ(CallerOver(ReadFile(dir_ / "stranger.pem")).status().code(), absl::StatusCode::kUnavailable)
      << "a client trusting another CA got in";
}

TEST_F(TlsTest, HttpsVerifiesTheServerAndPlainHttpIsRefused) {
  httplib::SSLClient https("localhost", server_->http_port());
  https.set_ca_cert_path((dir_ / "server.pem").c_str());
  https.enable_server_certificate_verification(true);
  https.set_bearer_token_auth(token_.c_str());
  auto health = https.Get("/healthz");
  ASSERT_TRUE(health) << httplib::to_string(health.error());
  EXPECT_EQ(health->status, 200);
  auto runs = https.Get("/v1/runs");
  ASSERT_TRUE(runs);
  EXPECT_EQ(runs->status, 200) << runs->body;

  httplib::SSLClient stranger("localhost", server_->http_port());
  stranger.set_ca_cert_path((dir_ / "stranger.pem").c_str());
  stranger.enable_server_certificate_verification(true);
  EXPECT_FALSE(stranger.Get("/healthz")) << "a client trusting another CA got an answer";

  httplib::Client plain("127.0.0.1", server_->http_port());
  plain.set_connection_timeout(5s);
  plain.set_read_timeout(5s);
  auto clear = plain.Get("/healthz");
  EXPECT_TRUE(!clear || clear->status != 200) << "plain HTTP got an answer";
}

TEST_F(TlsTest, TheCliTakesACaFileAndRefusesOneItCannotRead) {
  const std::string address = "localhost:" + std::to_string(server_->grpc_port());
  auto fleet = RunToCompletion({INSDIAG_CLI_PATH, "fleet", "stats", "--server", address, "--token", token_,
                                "--ca-file", (dir_ / "server.pem").string()},
                               dir_, 60s);
  ASSERT_TRUE(fleet.ok());
  EXPECT_EQ(fleet->exit_status, 0) << fleet->stderr_text;
  auto missing = RunToCompletion({INSDIAG_CLI_PATH, "fleet", "stats", "--server", address, "--token", token_,
                                  "--ca-file", (dir_ / "missing.pem").string()},
                                 dir_, 60s);
  ASSERT_TRUE(missing.ok());
  EXPECT_EQ(missing->exit_status, 2);
  EXPECT_THAT(missing->stderr_text, HasSubstr("missing.pem"));
}

// The Python example client over TLS: it verifies the server against
// --ca-file (or $INSDIAG_CA_FILE) and sends the token of $INSDIAG_TOKEN.
TEST_F(TlsTest,
       ThePythonClientVerifiesTheServerAgainstItsCaFileAndTakesItsTokenFromTheEnvironment) {
  auto simulated =
      RunToCompletion({INSDIAG_CLI_PATH, "simulate", (dir_ / "run.csv").string(), "--profile",
                       "static", "--rate", "10", "--seed", "7", "--serial", "INS-PY-TLS"},
                      dir_, 60s);
  ASSERT_TRUE(simulated.ok() && simulated->exit_status == 0)
      << (simulated.ok() ? simulated->stderr_text : "");
  const std::string operator_token = MakeToken(pool(), v1::OPERATOR, "python over tls");
  const std::string address = "localhost:" + std::to_string(server_->grpc_port());
  const auto python = [&](std::vector<std::string> args, const std::vector<std::string>& env) {
    args.insert(args.begin(),
                {"/usr/bin/python3", INSDIAG_SOURCE_DIR "/clients/python/insdiag_client.py",
                 (dir_ / "run.csv").string(), "--server", address, "--stubs-dir",
                 (dir_ / "stubs").string()});
    auto done = RunToCompletion(args, dir_, 180s, env);
    EXPECT_TRUE(done.ok()) << done.status();
    return done.ok() ? *done : Completed{};
  };
  const std::string token_env = "INSDIAG_TOKEN=" + operator_token;

  auto diagnosed = python({"--ca-file", (dir_ / "server.pem").string(), "--json"}, {token_env});
  EXPECT_EQ(diagnosed.exit_status, 0) << diagnosed.stderr_text;
  EXPECT_THAT(diagnosed.stderr_text, HasSubstr("uploaded runs/"));
  EXPECT_THAT(diagnosed.stdout_text, HasSubstr("\"candidates\""));

  // The CA file from the environment; a server its CA did not sign is refused.
  auto stranger = python({}, {token_env, "INSDIAG_CA_FILE=" + (dir_ / "stranger.pem").string()});
  EXPECT_EQ(stranger.exit_status, 1);
  EXPECT_THAT(stranger.stderr_text, HasSubstr("UNAVAILABLE"));
  auto from_env = python({}, {token_env, "INSDIAG_CA_FILE=" + (dir_ / "server.pem").string()});
  EXPECT_EQ(from_env.exit_status, 0) << from_env.stderr_text;
  // Without a token the server refuses; without a CA file the client cannot speak TLS.
  auto anonymous = python({"--ca-file", (dir_ / "server.pem").string()}, {"INSDIAG_TOKEN="});
  EXPECT_EQ(anonymous.exit_status, 1);
  EXPECT_THAT(anonymous.stderr_text, HasSubstr("UNAUTHENTICATED"));
  auto missing = python({"--ca-file", (dir_ / "missing.pem").string()}, {token_env});
  EXPECT_EQ(missing.exit_status, 2);
  EXPECT_THAT(missing.stderr_text, HasSubstr("missing.pem"));
}

TEST(TlsOptions, AServerWithoutItsKeyOrWithABadCertificateDoesNotStart) {
  const auto dir = MakeTempDir("insdiag-tls-bad");
  std::ofstream(dir / "bad.pem") << "not a certificate\n";
  server::InsdiagServer::Options options;
  options.grpc_port = 0;
  options.http_port = 0;
  options.tls_cert_file = (dir / "bad.pem").string();
  // Refused before any database work: no pool is touched.
  auto database = ScratchDatabase::Create();
  if (!database.ok()) GTEST_SKIP() << database.status();
  auto pool = kb::ConnectionPool::Create({.database_url = (*database)->url(), .max_connections = 2});
  ASSERT_TRUE(pool.ok());
  auto no_key = server::InsdiagServer::Start(**pool, options);
  EXPECT_EQ(no_key.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(no_key.status().message(), HasSubstr("--tls-key"));
  options.tls_key_file = (dir / "bad.pem").string();
  auto bad = server::InsdiagServer::Start(**pool, options);
  EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(bad.status().message(), HasSubstr("bad.pem"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace insdiag::testing
