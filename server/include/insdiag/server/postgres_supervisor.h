// The embedded PostgreSQL: a cluster of the installed PostgreSQL under the
// server's data directory, started with the server and stopped with it.
//
//   <data_dir>/pg/    the cluster (initdb --no-sync -A trust, on first start)
//   <data_dir>/run/   its unix socket and server log; no TCP listener
//
// As root, initdb and pg_ctl run as the `postgres` user (initdb refuses
// root), which then owns both directories.
//
// One server per data directory: the supervisor holds an flock on
// <data_dir>/insdiagd.lock while it lives, and a second server on the same
// directory is refused. No PostgreSQL outlives its server: beside each
// postmaster it starts a guard process, which asks that postmaster for a
// fast shutdown when the server's end of a pipe closes, i.e. when the server
// exits, killed or aborted included. A cluster found running at start (an
// orphan of a server the guard could not stop: the guard itself killed) is
// stopped and started again under a new guard. A cluster that stops while the supervisor runs (a crash, a shutdown for want
// of disk space) is started again: the supervisor looks for it every
// `restart_check_interval` and starts it when it finds it stopped twice in a
// row; the server reconnects by itself.
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <sys/types.h>
#include <thread>
#include <vector>

namespace insdiag::server {

class PostgresSupervisor {
 public:
  struct Options {
    std::filesystem::path data_dir;
    // PostgreSQL's bin directory; empty: the newest /usr/lib/postgresql/*/bin.
    std::filesystem::path bin_dir;
    std::string database = "insdiag";  // created when missing
    // How often the supervisor checks that the cluster runs; zero: never.
    std::chrono::milliseconds restart_check_interval = std::chrono::seconds(5);
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

  // How many times the cluster was found stopped and started again.
  int restarts() const;

 private:
  explicit PostgresSupervisor(Options options);
  absl::Status Run(const std::string& tool, const std::vector<std::string>& args) const;
  // pg_ctl start, then StartGuard.
  absl::Status StartCluster();
  // The flock on <data_dir>/insdiagd.lock; FAILED_PRECONDITION when another
  // process holds it.
  absl::Status LockDataDir();
  // The guard of the postmaster postmaster.pid names, replacing the guard
  // of an earlier postmaster.
  absl::Status StartGuard();
  // Closes the guard's pipe and reaps it.
  void StopGuard();
  // The watchdog thread: starts the cluster again whenever it finds it stopped.
  void KeepClusterRunning();

  Options options_;
  std::filesystem::path cluster_dir_;
  std::filesystem::path run_dir_;
  bool as_postgres_ = false;

  mutable std::mutex mutex_;  // the cluster's state and the pg_ctl calls
  std::condition_variable stopping_;
  bool running_ = false;
  int restarts_ = 0;
  std::thread watchdog_;
  int lock_fd_ = -1;
  pid_t guard_pid_ = 0;
  int guard_pipe_fd_ = -1;  // the write end; the guard reads to its end
};

}  // namespace insdiag::server
