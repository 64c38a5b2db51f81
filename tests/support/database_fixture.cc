#include "support/database_fixture.h"

#include <absl/strings/str_cat.h>
#include <libpq-fe.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <thread>

#include "insdiag/kb/migrations.h"

namespace insdiag::testing {
namespace {

std::string QuoteConninfoValue(std::string_view value) {
  std::string out = "'";
  for (const char c : value) {
    if (c == '\'' || c == '\\') out += '\\';
    out += c;
  }
  return out + "'";
}

// The template's name carries the migrations' checksums, so a cluster reused
// across edits of migrations/ never hands out a stale schema.
std::string TemplateName() {
  std::string all;
  for (const auto& migration : kb::EmbeddedMigrations()) all += kb::MigrationChecksum(migration);
  const auto key = static_cast<std::uint64_t>(kb::AdvisoryLockKey(all));
  return absl::StrCat("insdiag_template_", absl::Hex(key, absl::kZeroPad16));
}

absl::Status EnsureTemplate(kb::Connection& admin, const std::string& admin_url) {
  const std::string name = TemplateName();
  // Test processes run in parallel: one builds the template, the others
  // wait on the lock and then find it.
  if (auto locked = admin.Exec("SELECT pg_advisory_lock($1)", {kb::Param::Int(kb::AdvisoryLockKey(name))});
      !locked.ok()) {
    return locked.status();
  }
  absl::Status status = [&]() -> absl::Status {
    auto exists = admin.Exec("SELECT 1 FROM pg_database WHERE datname = $1", {kb::Param::Text(name)});
    if (!exists.ok()) return exists.status();
    if (exists->rows() > 0) return absl::OkStatus();
    // Built under another name and renamed when complete: a crash half-way
    // never leaves a half-migrated template behind.
    const std::string building = name + "_building";
    if (auto s = admin.ExecScript(absl::StrCat("DROP DATABASE IF EXISTS ", building, " WITH (FORCE)")); !s.ok()) {
      return s;
    }
    if (auto s = admin.ExecScript(absl::StrCat("CREATE DATABASE ", building)); !s.ok()) return s;
    {
      auto db = kb::Connection::Open(WithDatabaseName(admin_url, building));
      if (!db.ok()) return db.status();
      if (auto applied = kb::ApplyMigrations(*db, kb::EmbeddedMigrations()); !applied.ok()) {
        return applied.status();
      }
    }
    return admin.ExecScript(absl::StrCat("ALTER DATABASE ", building, " RENAME TO ", name));
  }();
  (void)admin.Exec("SELECT pg_advisory_unlock($1)", {kb::Param::Int(kb::AdvisoryLockKey(name))});
  return status;
}

}  // namespace

std::optional<std::string> AdminDatabaseUrl() {
  const char* url = std::getenv("INSDIAG_TEST_DATABASE_URL");
  if (url == nullptr || *url == '\0') return std::nullopt;
  return std::string(url);
}

std::string WithDatabaseName(const std::string& url, const std::string& name) {
  char* error = nullptr;
  PQconninfoOption* options = PQconninfoParse(url.c_str(), &error);
  if (options == nullptr) {
    PQfreemem(error);
    return url;
  }
  std::string out = absl::StrCat("dbname=", QuoteConninfoValue(name));
  for (PQconninfoOption* option = options; option->keyword != nullptr; ++option) {
    if (option->val == nullptr || std::string_view(option->keyword) == "dbname") continue;
    absl::StrAppend(&out, " ", option->keyword, "=", QuoteConninfoValue(option->val));
  }
  PQconninfoFree(options);
  return out;
}

absl::StatusOr<std::unique_ptr<ScratchDatabase>> ScratchDatabase::Create(bool migrated) {
  const auto admin_url = AdminDatabaseUrl();
  if (!admin_url) return absl::FailedPreconditionError("INSDIAG_TEST_DATABASE_URL is not set");
  auto admin = kb::Connection::Open(*admin_url);
  if (!admin.ok()) return admin.status();
  std::string create = "CREATE DATABASE ";
  static std::atomic<int> counter{0};
  const std::string name = absl::StrCat("insdiag_test_", getpid(), "_", counter++);
  absl::StrAppend(&create, name);
  if (migrated) {
    if (auto status = EnsureTemplate(*admin, *admin_url); !status.ok()) return status;
    absl::StrAppend(&create, " TEMPLATE ", TemplateName());
  }
  // Cloning fails while another session is still connected to the template
  // (a sibling process finishing its migration): retry briefly.
  absl::Status status;
  for (int attempt = 0; attempt < 50; ++attempt) {
    status = admin->ExecScript(create);
    if (status.ok() || status.message().find("being accessed by other users") == std::string::npos) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  if (!status.ok()) return status;
  return std::unique_ptr<ScratchDatabase>(new ScratchDatabase(*admin_url, name));
}

ScratchDatabase::ScratchDatabase(std::string admin_url, std::string name)
    : admin_url_(std::move(admin_url)), name_(std::move(name)), url_(WithDatabaseName(admin_url_, name_)) {}

ScratchDatabase::~ScratchDatabase() {
  if (auto admin = kb::Connection::Open(admin_url_); admin.ok()) {
    (void)admin->ExecScript(absl::StrCat("DROP DATABASE IF EXISTS ", name_, " WITH (FORCE)"));
  }
}

void DatabaseTest::SetUp() {
  if (!AdminDatabaseUrl()) {
    GTEST_SKIP() << "INSDIAG_TEST_DATABASE_URL is not set: run under scripts/with-throwaway-pg.sh (./test.sh does)";
  }
  auto database = ScratchDatabase::Create();
  ASSERT_TRUE(database.ok()) << database.status();
  database_ = std::move(*database);
  auto pool = kb::ConnectionPool::Create({.database_url = database_->url(), .max_connections = 4});
  ASSERT_TRUE(pool.ok()) << pool.status();
  pool_ = std::move(*pool);
}

void DatabaseTest::TearDown() {
  pool_.reset();
  database_.reset();
}

}  // namespace insdiag::testing
