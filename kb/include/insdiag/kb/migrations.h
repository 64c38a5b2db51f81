// Schema migrations: numbered SQL files `migrations/NNNN_name.sql`, applied in
// order, each in its own transaction, under a PostgreSQL advisory lock (so
// replicas starting together apply each file once), and recorded with their
// SHA-256 in `schema_migrations(version, name, sha256, applied_at)`.
//
// A file whose content changed after it was applied makes Apply fail: the
// database no longer matches what the files say it is.
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "insdiag/kb/pg.h"

namespace insdiag::kb {

struct Migration {
  int version = 0;       // NNNN of the file name
  std::string name;      // file name, e.g. "0001_runs.sql"
  std::string sql;
};

// The migrations built into this binary from migrations/ (in version order).
std::span<const Migration> EmbeddedMigrations();

// Reads `dir/NNNN_*.sql` in version order. INVALID_ARGUMENT for a malformed
// name or a duplicate version.
absl::StatusOr<std::vector<Migration>> LoadMigrationsFromDirectory(const std::filesystem::path& dir);

// Lower-case hex SHA-256 of a migration's text, as recorded.
std::string MigrationChecksum(const Migration& migration);

struct MigrationReport {
  int applied = 0;          // applied by this call
  int already_applied = 0;  // found recorded and unchanged
};

// Applies what is missing. FAILED_PRECONDITION naming the file when an
// applied migration's text changed, or when the database records a version
// this binary does not know (it is newer than the server).
absl::StatusOr<MigrationReport> ApplyMigrations(Connection& connection,
                                                std::span<const Migration> migrations);

}  // namespace insdiag::kb
