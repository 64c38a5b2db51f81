// A test against the real insdiagd on the test's own database (DatabaseTest):
// the server started by the fixture's SetUp through StartServer, stopped with
// SIGTERM in TearDown, and its working directory removed.
#pragma once

#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>

#include "support/database_fixture.h"
#include "support/insdiagd_process.h"
#include "support/subprocess.h"

namespace insdiag::testing {

class ServerProcessTest : public DatabaseTest {
 protected:
  // Starts `insdiagd_path` on the test's database, its files under a fresh
  // directory named after `prefix`. Call after DatabaseTest::SetUp, unless
  // it skipped.
  void StartServer(const std::string& insdiagd_path, const std::string& prefix) {
    dir_ = MakeTempDir(prefix);
    auto server = StartInsdiagd(insdiagd_path, database_url(), dir_);
    ASSERT_TRUE(server.ok()) << server.status();
    server_ = std::move(server->process);
    address_ = server->grpc_address;
    http_port_ = server->http_port;
    token_ = server->admin_token;  // written by insdiagd's first start on this database
  }

  void TearDown() override {
    if (server_) {
      server_->Signal(SIGTERM);
      server_->Wait(std::chrono::seconds(30));
    }
    server_.reset();
    if (!dir_.empty()) std::filesystem::remove_all(dir_);
    DatabaseTest::TearDown();
  }

  std::filesystem::path dir_;
  std::unique_ptr<Subprocess> server_;
  std::string address_;  // gRPC, "127.0.0.1:N"
  int http_port_ = 0;
  std::string token_;    // the admin's
};

}  // namespace insdiag::testing
