// The server tests' fixture: an InsdiagServer on 127.0.0.1 with ephemeral
// ports over a fresh migrated database, a real gRPC stub and a real HTTP
// client.
#pragma once

#include <memory>

#include "insdiag/client/run_client.h"
#include "insdiag/v1/analyses.grpc.pb.h"
#include "insdiag/kb/access_store.h"
#include "insdiag/server/insdiag_server.h"
#include "support/database_fixture.h"

// Last: httplib.h pulls in <resolv.h>, whose `_res` macro breaks Eigen.
#include <httplib.h>

namespace insdiag::testing {

// A token of `role` made directly in the database; its secret.
std::string MakeToken(kb::ConnectionPool& pool, v1::Role role, const std::string& display_name = "");

class ServerTest : public DatabaseTest {
 protected:
  void SetUp() override;
  void TearDown() override;
  // Runs on the fresh database before the server, and so its analysis
  // workers, start: for stores written directly, which a worker would race.
  virtual void BeforeServerStarts() {}
  // The server's options beyond the fixture's (loopback, ephemeral ports).
  virtual void Configure(server::InsdiagServer::Options& /*options*/) {}

  v1::RunService::Stub& runs() { return *runs_; }
  httplib::Client& http() { return *http_; }
  std::shared_ptr<grpc::Channel> channel() { return channel_; }

  // Count of stored runs, through the API.
  int StoredRunCount();

  // The fixture's clients act as ADMIN with this secret.
  std::string admin_token_;

  std::unique_ptr<server::InsdiagServer> server_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::RunService::Stub> runs_;
  std::unique_ptr<httplib::Client> http_;
};

}  // namespace insdiag::testing
