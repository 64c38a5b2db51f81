// The `db` tests' harness. ctest runs under scripts/with-throwaway-pg.sh,
// which exports INSDIAG_TEST_DATABASE_URL (the throwaway cluster's
// `postgres` database). Each test gets a fresh database cloned from a
// migrated template that is built once per cluster; tests are skipped with a
// message when the variable is absent.
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <optional>
#include <string>

#include "insdiag/kb/connection_pool.h"

namespace insdiag::testing {

// INSDIAG_TEST_DATABASE_URL, when set.
std::optional<std::string> AdminDatabaseUrl();

// `url` (URL or key=value form) pointing at database `name` instead.
std::string WithDatabaseName(const std::string& url, const std::string& name);

// A database of its own, cloned from the migrated template; dropped on
// destruction.
class ScratchDatabase {
 public:
  // `migrated` false gives an empty database (for migration tests).
  static absl::StatusOr<std::unique_ptr<ScratchDatabase>> Create(bool migrated = true);
  ~ScratchDatabase();
  ScratchDatabase(const ScratchDatabase&) = delete;
  ScratchDatabase& operator=(const ScratchDatabase&) = delete;

  const std::string& url() const { return url_; }
  const std::string& name() const { return name_; }

 private:
  ScratchDatabase(std::string admin_url, std::string name);
  std::string admin_url_;
  std::string name_;
  std::string url_;
};

// Base fixture of the `db` tests: a fresh migrated database and a pool on it.
class DatabaseTest : public ::testing::Test {
 protected:
  void SetUp() override;
  void TearDown() override;

  const std::string& database_url() const { return database_->url(); }
  kb::ConnectionPool& pool() { return *pool_; }

  std::unique_ptr<ScratchDatabase> database_;
  std::unique_ptr<kb::ConnectionPool> pool_;
};

}  // namespace insdiag::testing
