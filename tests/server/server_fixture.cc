#include "server_fixture.h"

#include <gtest/gtest.h>

#include "access_codec.h"

namespace insdiag::testing {

std::string MakeToken(kb::ConnectionPool& pool, v1::Role role, const std::string& display_name) {
  kb::AccessStore store(pool);
  kb::Token token;
  token.display_name = display_name.empty() ? "test " + v1::Role_Name(role) : display_name;
  token.role = server::RoleOf(role);
  auto created = store.CreateToken(token, "test fixture");
  EXPECT_TRUE(created.ok()) << created.status();
  return created.ok() ? created->secret : "";
}

void ServerTest::SetUp() {
  DatabaseTest::SetUp();
  if (IsSkipped() || HasFatalFailure()) return;
  BeforeServerStarts();
  if (HasFatalFailure()) return;
  server::InsdiagServer::Options options;
  options.bind_address = "127.0.0.1";
  options.grpc_port = 0;
  options.http_port = 0;
  Configure(options);
  auto started = server::InsdiagServer::Start(pool(), options);
  ASSERT_TRUE(started.ok()) << started.status();
  server_ = std::move(*started);
  admin_token_ = MakeToken(pool(), v1::ADMIN);
  channel_ = client::Connect("127.0.0.1:" + std::to_string(server_->grpc_port()), admin_token_);
  runs_ = v1::RunService::NewStub(channel_);
  http_ = std::make_unique<httplib::Client>("127.0.0.1", server_->http_port());
  http_->set_read_timeout(std::chrono::seconds(60));
  http_->set_write_timeout(std::chrono::seconds(60));
  http_->set_bearer_token_auth(admin_token_.c_str());
}

void ServerTest::TearDown() {
  http_.reset();
  runs_.reset();
  channel_.reset();
  if (server_) server_->Shutdown();
  server_.reset();
  DatabaseTest::TearDown();
}

int ServerTest::StoredRunCount() {
  grpc::ClientContext context;
  v1::ListRunsRequest request;
  request.set_page_size(1000);
  v1::ListRunsResponse response;
  const grpc::Status status = runs_->ListRuns(&context, request, &response);
  EXPECT_TRUE(status.ok()) << status.error_message();
  return response.runs_size();
}

}  // namespace insdiag::testing
