#include "insdiag/kb/migrations.h"

#include <absl/strings/escaping.h>
#include <absl/strings/numbers.h>
#include <absl/strings/str_cat.h>

#include <algorithm>
#include <array>
#include <fstream>
#include <map>
#include <sstream>

#include "insdiag/api/sha256.h"
#include "insdiag/engine/status_macros.h"

namespace insdiag::kb {
namespace {

constexpr std::string_view kLockName = "insdiag.schema_migrations";

absl::StatusOr<int> VersionOf(const std::string& file_name) {
  int version = 0;
  const auto underscore = file_name.find('_');
  if (underscore != 4 || !file_name.ends_with(".sql") ||
      !absl::SimpleAtoi(file_name.substr(0, 4), &version)) {
    return absl::InvalidArgumentError(
        absl::StrCat("migration file ", file_name, " is not named NNNN_name.sql"));
  }
  return version;
}

// Unlocks on every return path; the lock is session-level, so a failed
// transaction does not release it.
class AdvisoryLock {
 public:
  static absl::StatusOr<AdvisoryLock> Take(Connection& connection, std::int64_t key) {
    INSDIAG_ASSIGN_OR_RETURN(auto locked,
                             connection.Exec("SELECT pg_advisory_lock($1)", {Param::Int(key)}));
    return AdvisoryLock(connection, key);
  }
  AdvisoryLock(AdvisoryLock&& other) noexcept : connection_(other.connection_), key_(other.key_) {
    other.connection_ = nullptr;
  }
  AdvisoryLock& operator=(AdvisoryLock&&) = delete;
  ~AdvisoryLock() {
    if (connection_) (void)connection_->Exec("SELECT pg_advisory_unlock($1)", {Param::Int(key_)});
  }

 private:
  AdvisoryLock(Connection& connection, std::int64_t key) : connection_(&connection), key_(key) {}
  Connection* connection_;
  std::int64_t key_;
};

}  // namespace

absl::StatusOr<std::vector<Migration>> LoadMigrationsFromDirectory(const std::filesystem::path& dir) {
  std::error_code error;
  std::vector<Migration> migrations;
  for (const auto& entry : std::filesystem::directory_iterator(dir, error)) {
    const std::string file_name = entry.path().filename().string();
    if (!file_name.ends_with(".sql")) continue;
    INSDIAG_ASSIGN_OR_RETURN(auto version, VersionOf(file_name));
    std::ifstream in(entry.path(), std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    if (!in) return absl::NotFoundError(absl::StrCat("cannot read ", entry.path().string()));
    migrations.push_back(Migration{version, file_name, text.str()});
  }
  if (error) return absl::NotFoundError(absl::StrCat("cannot list ", dir.string(), ": ", error.message()));
  std::sort(migrations.begin(), migrations.end(),
            [](const Migration& a, const Migration& b) { return a.version < b.version; });
  for (std::size_t i = 1; i < migrations.size(); ++i) {
    if (migrations[i].version == migrations[i - 1].version) {
      return absl::InvalidArgumentError(absl::StrCat("migrations ", migrations[i - 1].name, " and ",
                                                     migrations[i].name, " share a version"));
    }
  }
  return migrations;
}

std::string MigrationChecksum(const Migration& migration) {
  return absl::BytesToHexString(api::Sha256(migration.sql));
}

absl::StatusOr<MigrationReport> ApplyMigrations(Connection& connection,
                                                std::span<const Migration> migrations) {
  INSDIAG_ASSIGN_OR_RETURN(auto lock, AdvisoryLock::Take(connection, AdvisoryLockKey(kLockName)));

  if (auto created = connection.Exec(
          "CREATE TABLE IF NOT EXISTS schema_migrations ("
          " version integer PRIMARY KEY,"
          " name text NOT NULL,"
          " sha256 text NOT NULL,"
          " applied_at timestamptz NOT NULL DEFAULT now())");
      !created.ok()) {
    return created.status();
  }
  INSDIAG_ASSIGN_OR_RETURN(
      auto recorded,
      connection.Exec("SELECT version, name, sha256 FROM schema_migrations ORDER BY version"));

  std::map<int, const Migration*> by_version;
  for (const auto& migration : migrations) by_version[migration.version] = &migration;

  MigrationReport report;
  std::map<int, bool> done;
  for (int row = 0; row < recorded.rows(); ++row) {
    INSDIAG_ASSIGN_OR_RETURN(auto version, recorded.Int(row, 0));
    const std::string recorded_name = recorded.String(row, 1);
    const auto known = by_version.find(static_cast<int>(version));
    if (known == by_version.end()) {
      return absl::FailedPreconditionError(absl::StrCat(
          "the database has migration ", recorded_name,
          " applied, which this server does not know: the database is newer than the server"));
    }
    const std::string checksum = MigrationChecksum(*known->second);
    if (checksum != recorded.String(row, 2)) {
      return absl::FailedPreconditionError(
          absl::StrCat("migration ", known->second->name, " has changed since it was applied as ",
                       recorded_name, " (recorded sha256 ", recorded.String(row, 2), ", file now ",
                       checksum, "); add a new migration instead of editing an applied one"));
    }
    done[known->first] = true;
    ++report.already_applied;
  }

  for (const auto& migration : migrations) {
    if (done.contains(migration.version)) continue;
    const absl::Status applied = connection.InTransaction([&]() -> absl::Status {
      INSDIAG_RETURN_IF_ERROR(connection.ExecScript(migration.sql));
      return connection
          .Exec("INSERT INTO schema_migrations (version, name, sha256) VALUES ($1, $2, $3)",
                {Param::Int(migration.version), Param::Text(migration.name),
                 Param::Text(MigrationChecksum(migration))})
          .status();
    });
    if (!applied.ok()) {
      return absl::Status(applied.code(),
                          absl::StrCat("migration ", migration.name, " failed: ", applied.message()));
    }
    ++report.applied;
  }
  return report;
}

}  // namespace insdiag::kb
