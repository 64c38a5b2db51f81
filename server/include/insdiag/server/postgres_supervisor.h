// The embedded PostgreSQL: a cluster of the installed PostgreSQL under the
// server's data directory, started with the server and stopped with it.
//
//   <data_dir>/pg/    the cluster (initdb --no-sync -A trust, on first start)
//   <data_dir>/run/   its unix socket and server log; no TCP listener
//
// As root, initdb and pg_ctl run as the `postgres` user (initdb refuses
// root), which then owns both directories. A cluster left running by a
// crashed server is adopted, and stopped when this supervisor stops.
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace insdiag::server {

class PostgresSupervisor {
 public:
  struct Options {
    std::filesystem::path data_dir;
    // PostgreSQL's bin directory; empty: the newest /usr/lib/postgresql/*/bin.
    std::filesystem::path bin_dir;
    std::string database = "insdiag";  // created when missing
  };

  // Initialises (if needed) and starts the cluster and creates the database.
  // FAILED_PRECONDITION with the reason (no PostgreSQL installed, a data
  // directory the postgres user cannot reach, a socket path too long) and
  // INTERNAL with the tail of the tool's output when initdb or pg_ctl fail.
  static absl::StatusOr<std::unique_ptr<PostgresSupervisor>> Start(Options options);

  ~PostgresSupervisor();
  PostgresSupervisor(const PostgresSupervisor&) = delete;
  PostgresSupervisor& operator=(const PostgresSupervisor&) = delete;

  // libpq connection string of the database.
  std::string database_url() const;
  const std::filesystem::path& cluster_dir() const { return cluster_dir_; }

  // pg_ctl stop -m fast; idempotent. Also run by the destructor.
  absl::Status Stop();

 private:
  explicit PostgresSupervisor(Options options);
  absl::Status Run(const std::string& tool, const std::vector<std::string>& args) const;

  Options options_;
  std::filesystem::path cluster_dir_;
  std::filesystem::path run_dir_;
  bool as_postgres_ = false;
  bool running_ = false;
};

}  // namespace insdiag::server
