// Tokens and what they protect, through real gRPC and HTTP clients against
// the in-process server: tokens expire and are revoked, REST says 401 and
// 403, the audit trail is read by resource, the failure history outlives
// delete, and the first start makes one admin token. The role matrix over
// every method is role_matrix_test.cc.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <thread>

#include "insdiag/api/json.h"
#include "insdiag/client/unary.h"
#include "insdiag/kb/pg.h"
#include "insdiag/v1/access.grpc.pb.h"
#include "insdiag/v1/knowledge.grpc.pb.h"
#include "server_fixture.h"
#include "support/subprocess.h"
#include "support/synthetic_run.h"

namespace insdiag::testing {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;

class AccessTest : public ServerTest {
 protected:
  // A stored run, uploaded as ADMIN.
  std::string UploadedRun(int seed = 3) {
    auto run = client::UploadRun(runs(), SyntheticStaticRun(500, 50.0, seed), client::UploadOptions{});
    EXPECT_TRUE(run.ok()) << run.status();
    return run.ok() ? run->name() : "";
  }

  std::vector<v1::AuditEvent> AuditEvents(const std::string& resource = "") {
    auto stub = v1::AccessService::NewStub(channel());
    v1::ListAuditEventsRequest request;
    request.set_resource(resource);
    request.set_page_size(1000);
    auto events = client::CallUnary<v1::ListAuditEventsResponse>(
        [&](grpc::ClientContext* c, v1::ListAuditEventsResponse* r) { return stub->ListAuditEvents(c, request, r); });
    EXPECT_TRUE(events.ok()) << events.status();
    return events.ok() ? std::vector<v1::AuditEvent>(events->audit_events().begin(), events->audit_events().end())
                       : std::vector<v1::AuditEvent>{};
  }
};

TEST_F(AccessTest, TokensAreCreatedListedRevokedAndExpireAndTheSecretIsStoredOnlyHashed) {
  auto admin = v1::AccessService::NewStub(channel());
  v1::CreateTokenRequest request;
  request.mutable_token()->set_display_name("bench-3 uploader");
  request.mutable_token()->set_role(v1::OPERATOR);
  auto created = client::CallUnary<v1::CreatedToken>(
      [&](grpc::ClientContext* c, v1::CreatedToken* r) { return admin->CreateToken(c, request, r); });
  ASSERT_TRUE(created.ok()) << created.status();
  EXPECT_THAT(created->secret(), ::testing::MatchesRegex("insdiag_[A-Za-z0-9_-]{43}"));

  // The secret works, and is nowhere in the database.
  auto as_operator = v1::AccessService::NewStub(
      client::Connect("127.0.0.1:" + std::to_string(server_->grpc_port()), created->secret()));
  auto caller = client::CallUnary<v1::Caller>([&](grpc::ClientContext* c, v1::Caller* r) {
    return as_operator->GetCaller(c, v1::GetCallerRequest(), r);
  });
  ASSERT_TRUE(caller.ok()) << caller.status();
  EXPECT_EQ(caller->display_name(), "bench-3 uploader");
  EXPECT_EQ(caller->role(), v1::OPERATOR);
  auto db = kb::Connection::Open(database_url());
  ASSERT_TRUE(db.ok());
  auto leaked = db->Exec("SELECT count(*) FROM access_tokens WHERE position(convert_to($1, 'UTF8') in secret_sha256) > 0 "
                         "OR display_name = $1 OR creator = $1",
                         {kb::Param::Text(created->secret())});
  ASSERT_TRUE(leaked.ok()) << leaked.status();
  EXPECT_EQ(leaked->String(0, 0), "0");

  // Listed, then revoked: refused from then on, saying so.
  auto listed = client::CallUnary<v1::ListTokensResponse>([&](grpc::ClientContext* c, v1::ListTokensResponse* r) {
    return admin->ListTokens(c, v1::ListTokensRequest(), r);
  });
  ASSERT_TRUE(listed.ok());
  EXPECT_TRUE(std::any_of(listed->tokens().begin(), listed->tokens().end(),
                          [&](const v1::Token& t) { return t.name() == created->token().name(); }));
  v1::RevokeTokenRequest revoke;
  revoke.set_name(created->token().name());
  auto revoked = client::CallUnary<v1::Token>(
      [&](grpc::ClientContext* c, v1::Token* r) { return admin->RevokeToken(c, revoke, r); });
  ASSERT_TRUE(revoked.ok()) << revoked.status();
  EXPECT_TRUE(revoked->has_revoke_time());
  auto refused = client::CallUnary<v1::Caller>([&](grpc::ClientContext* c, v1::Caller* r) {
    return as_operator->GetCaller(c, v1::GetCallerRequest(), r);
  });
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kUnauthenticated);
  EXPECT_THAT(refused.status().message(), HasSubstr("revoked"));

  // An expiry in the past is refused; one a second away stops working after it.
  request.mutable_token()->mutable_expire_time()->set_seconds(std::time(nullptr) - 10);
  auto past = client::CallUnary<v1::CreatedToken>(
      [&](grpc::ClientContext* c, v1::CreatedToken* r) { return admin->CreateToken(c, request, r); });
  EXPECT_EQ(past.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(past.status().message(), HasSubstr("token.expire_time"));
  request.mutable_token()->mutable_expire_time()->set_seconds(std::time(nullptr) + 2);
  auto brief = client::CallUnary<v1::CreatedToken>(
      [&](grpc::ClientContext* c, v1::CreatedToken* r) { return admin->CreateToken(c, request, r); });
  ASSERT_TRUE(brief.ok()) << brief.status();
  std::this_thread::sleep_for(3s);
  auto as_expired = v1::AccessService::NewStub(
      client::Connect("127.0.0.1:" + std::to_string(server_->grpc_port()), brief->secret()));
  auto expired = client::CallUnary<v1::Caller>([&](grpc::ClientContext* c, v1::Caller* r) {
    return as_expired->GetCaller(c, v1::GetCallerRequest(), r);
  });
  EXPECT_EQ(expired.status().code(), absl::StatusCode::kUnauthenticated);
  EXPECT_THAT(expired.status().message(), HasSubstr("expired"));

  // A role is required.
  request.mutable_token()->clear_expire_time();
  request.mutable_token()->set_role(v1::ROLE_UNSPECIFIED);
  auto roleless = client::CallUnary<v1::CreatedToken>(
      [&](grpc::ClientContext* c, v1::CreatedToken* r) { return admin->CreateToken(c, request, r); });
  EXPECT_EQ(roleless.status().code(), absl::StatusCode::kInvalidArgument);
}

TEST_F(AccessTest, RestAnswers401WithTheSchemeAnd403ForALowRoleWhileHealthStaysOpen) {
  const std::string run = UploadedRun();
  httplib::Client anonymous("127.0.0.1", server_->http_port());
  auto health = anonymous.Get("/healthz");
  ASSERT_TRUE(health);
  EXPECT_EQ(health->status, 200);
  auto unauthenticated = anonymous.Get("/v1/runs");
  ASSERT_TRUE(unauthenticated);
  EXPECT_EQ(unauthenticated->status, 401);
  EXPECT_EQ(unauthenticated->get_header_value("WWW-Authenticate"), R"(Bearer realm="insdiag")");
  EXPECT_THAT(unauthenticated->body, HasSubstr("UNAUTHENTICATED"));
  auto download = anonymous.Get(("/v1/" + run + ":download").c_str());
  ASSERT_TRUE(download);
  EXPECT_EQ(download->status, 401);

  httplib::Client viewer("127.0.0.1", server_->http_port());
  viewer.set_bearer_token_auth(MakeToken(pool(), v1::VIEWER, "quality viewer").c_str());
  auto read = viewer.Get(("/v1/" + run).c_str());
  ASSERT_TRUE(read);
  EXPECT_EQ(read->status, 200);
  auto deleted = viewer.Delete(("/v1/" + run).c_str());
  ASSERT_TRUE(deleted);
  EXPECT_EQ(deleted->status, 403);
  EXPECT_THAT(deleted->body, HasSubstr("PERMISSION_DENIED"));
  EXPECT_THAT(deleted->body, HasSubstr("ADMIN"));
  EXPECT_EQ(StoredRunCount(), 1) << "a refused delete deleted";
}

TEST_F(AccessTest, EveryWriteLeavesAnAuditEventSayingWhoWhatWhenAndFromWhere) {
  const std::string run = UploadedRun();
  // A refused write over REST, by a viewer.
  httplib::Client viewer("127.0.0.1", server_->http_port());
  viewer.set_bearer_token_auth(MakeToken(pool(), v1::VIEWER, "curious viewer").c_str());
  ASSERT_TRUE(viewer.Delete(("/v1/" + run).c_str()));
  // An admitted write over REST, by the admin.
  auto analysis = http().Post("/v1/analyses", R"({"run":")" + run + R"("})", "application/json");
  ASSERT_TRUE(analysis);
  ASSERT_EQ(analysis->status, 200) << analysis->body;
  // A read leaves nothing.
  ASSERT_TRUE(http().Get(("/v1/" + run).c_str()));

  const auto events = AuditEvents();
  ASSERT_EQ(events.size(), 3u);  // newest first
  const v1::AuditEvent& created = events[0];
  EXPECT_EQ(created.method(), "insdiag.v1.AnalysisService.CreateAnalysis");
  EXPECT_THAT(created.resource(), ::testing::StartsWith("analyses/"));
  EXPECT_EQ(created.code(), "OK");
  EXPECT_EQ(created.role(), v1::ADMIN);
  EXPECT_THAT(created.peer(), ::testing::StartsWith("ipv4:127.0.0.1:")) << "REST calls name the HTTP client";
  const v1::AuditEvent& refused = events[1];
  EXPECT_EQ(refused.method(), "insdiag.v1.RunService.DeleteRun");
  EXPECT_EQ(refused.display_name(), "curious viewer");
  EXPECT_EQ(refused.code(), "PERMISSION_DENIED");
  const v1::AuditEvent& uploaded = events[2];
  EXPECT_EQ(uploaded.method(), "insdiag.v1.RunService.UploadRun");
  EXPECT_EQ(uploaded.resource(), run);
  EXPECT_EQ(uploaded.code(), "OK");
  EXPECT_THAT(uploaded.peer(), ::testing::StartsWith("ipv4:127.0.0.1:")) << "gRPC calls name the peer";
  EXPECT_LE(uploaded.event_time().seconds(), created.event_time().seconds());
  // Filtered by resource, over REST.
  auto by_run = http().Get(("/v1/auditEvents?resource=" + run).c_str());
  ASSERT_TRUE(by_run);
  ASSERT_EQ(by_run->status, 200) << by_run->body;
  v1::ListAuditEventsResponse listed;
  ASSERT_TRUE(api::FromJson(by_run->body, &listed).ok());
  EXPECT_EQ(listed.audit_events_size(), 1);  // the upload; the refused delete named no resource it reached
}

TEST_F(AccessTest, ARunThatADiagnosisRestsOnIsNotDeletedAndNothingOfItIsLost) {
  const std::string run = UploadedRun();
  const std::string run_id = run.substr(run.find('/') + 1);
  // A diagnosis on one of its analyses, as the knowledge base stores it.
  auto db = kb::Connection::Open(database_url());
  ASSERT_TRUE(db.ok());
  auto made = db->Exec(
      "WITH a AS (INSERT INTO analyses (run_id, unit_id) SELECT run_id, unit_id FROM runs "
      "WHERE run_id = $1::uuid RETURNING analysis_id, unit_id) "
      "INSERT INTO diagnoses (analysis_id, unit_id, fault_probability, top_module, top_failure_mode, "
      "top_probability, body) SELECT analysis_id, unit_id, 0.9, 'gyro.x', 'gyro_bias_drift', 0.9, '' FROM a",
      {kb::Param::Text(run_id)});
  ASSERT_TRUE(made.ok()) << made.status();
  ASSERT_EQ(made->AffectedRows(), 1);

  auto refused = http().Delete(("/v1/" + run).c_str());
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, 400) << refused->body;
  EXPECT_THAT(refused->body, HasSubstr("FAILED_PRECONDITION"));
  EXPECT_THAT(refused->body, HasSubstr("1 diagnoses"));
  EXPECT_EQ(StoredRunCount(), 1);
  auto kept = db->Exec("SELECT (SELECT count(*) FROM analyses), (SELECT count(*) FROM diagnoses)");
  ASSERT_TRUE(kept.ok());
  EXPECT_EQ(kept->String(0, 0), "1");
  EXPECT_EQ(kept->String(0, 1), "1");
  // The database itself keeps the promise, whoever deletes.
  auto direct = db->Exec("DELETE FROM runs WHERE run_id = $1::uuid", {kb::Param::Text(run_id)});
  EXPECT_EQ(direct.status().code(), absl::StatusCode::kFailedPrecondition);

  // A run without history goes, with its analyses.
  const std::string other = UploadedRun(4);
  auto gone = http().Delete(("/v1/" + other).c_str());
  ASSERT_TRUE(gone);
  EXPECT_EQ(gone->status, 200) << gone->body;
  EXPECT_EQ(StoredRunCount(), 1);
}

TEST_F(AccessTest, TheFirstStartWritesOneAdminTokenReadableOnlyByItsUser) {
  const auto dir = MakeTempDir("insdiag-first-admin");
  ASSERT_FALSE(dir.empty());
  // The fixture's own tokens: remove them, so that this database looks new.
  auto db = kb::Connection::Open(database_url());
  ASSERT_TRUE(db.ok());
  ASSERT_TRUE(db->Exec("DELETE FROM access_tokens").ok());
  server::InsdiagServer::Options options;
  options.grpc_port = 0;
  options.http_port = 0;
  options.workers.workers = 0;
  options.first_admin_token_file = dir / "data" / "admin-token";
  auto first = server::InsdiagServer::Start(pool(), options);
  ASSERT_TRUE(first.ok()) << first.status();
  EXPECT_TRUE((*first)->wrote_first_admin_token());
  EXPECT_EQ(std::filesystem::status(options.first_admin_token_file).permissions() & std::filesystem::perms::all,
            std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);
  std::string secret;
  std::ifstream(options.first_admin_token_file) >> secret;
  auto stub = v1::AccessService::NewStub(client::Connect("127.0.0.1:" + std::to_string((*first)->grpc_port()), secret));
  auto caller = client::CallUnary<v1::Caller>([&](grpc::ClientContext* c, v1::Caller* r) {
    return stub->GetCaller(c, v1::GetCallerRequest(), r);
  });
  ASSERT_TRUE(caller.ok()) << caller.status();
  EXPECT_EQ(caller->role(), v1::ADMIN);
  (*first)->Shutdown();

  // A later start leaves the token and its file alone.
  auto second = server::InsdiagServer::Start(pool(), options);
  ASSERT_TRUE(second.ok()) << second.status();
  EXPECT_FALSE((*second)->wrote_first_admin_token());
  std::string again;
  std::ifstream(options.first_admin_token_file) >> again;
  EXPECT_EQ(again, secret);
  (*second)->Shutdown();
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace insdiag::testing
