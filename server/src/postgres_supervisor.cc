#include "insdiag/server/postgres_supervisor.h"

#include <absl/strings/str_cat.h>
#include <absl/strings/str_join.h>
#include <fcntl.h>
#include <pwd.h>
#include <signal.h>
#include <spawn.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "insdiag/engine/status_macros.h"
#include "insdiag/kb/pg.h"
#include "insdiag/server/server_log.h"

extern char** environ;

namespace insdiag::server {
namespace {

// The guard of a postmaster (StartGuard): it reads its standard input, a
// pipe whose only writer is insdiagd, until the end, which comes when insdiagd
// exits however it exits (kill -9, abort); then, if postmaster.pid still
// names the postmaster it guards, it asks that postmaster for a fast shutdown
// (SIGINT). Shell builtins only: nothing to build or install.
constexpr char kGuardScript[] =
    "while read -r _; do :; done; "
    "read -r running < \"$2\" 2>/dev/null && [ \"$running\" = \"$1\" ] && kill -INT \"$1\"; exit 0";

// The socket name is <dir>/.s.PGSQL.<port>; sun_path holds 107 bytes.
constexpr std::size_t kMaxSocketPath = 107;
constexpr int kSocketPort = 5432;  // only a socket name: no TCP listener

std::filesystem::path FindBinDir() {
  std::vector<std::filesystem::path> candidates;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator("/usr/lib/postgresql", error)) {
    if (std::filesystem::exists(entry.path() / "bin" / "pg_ctl")) candidates.push_back(entry.path() / "bin");
  }
  // Newest major version: compare numerically ("15" > "9.6").
  std::sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) {
    return std::stod(a.parent_path().filename().string()) < std::stod(b.parent_path().filename().string());
  });
  return candidates.empty() ? std::filesystem::path() : candidates.back();
}

std::string Tail(const std::filesystem::path& file, std::size_t max_chars) {
  std::ifstream in(file);
  std::ostringstream text;
  text << in.rdbuf();
  std::string all = text.str();
  return all.size() > max_chars ? "…" + all.substr(all.size() - max_chars) : all;
}

}  // namespace

PostgresSupervisor::PostgresSupervisor(Options options)
    : options_(std::move(options)),
      cluster_dir_(options_.data_dir / "pg"),
      run_dir_(options_.data_dir / "run"),
      as_postgres_(::geteuid() == 0) {}

namespace {

// A child of its own process group, without the server's blocked signals:
// the server blocks SIGINT/SIGTERM to take them on its signal thread; the
// children must not inherit that, and a Ctrl-C at the terminal is for the
// server (which then stops PostgreSQL in order), not for them.
struct ChildAttributes {
  ChildAttributes() {
    posix_spawnattr_init(&attributes);
    sigset_t none;
    sigemptyset(&none);
    posix_spawnattr_setsigmask(&attributes, &none);
    sigset_t defaults;
    sigemptyset(&defaults);
    sigaddset(&defaults, SIGINT);
    sigaddset(&defaults, SIGTERM);
    posix_spawnattr_setsigdefault(&attributes, &defaults);
    posix_spawnattr_setpgroup(&attributes, 0);
    posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETPGROUP);
  }
  ~ChildAttributes() { posix_spawnattr_destroy(&attributes); }
  ChildAttributes(const ChildAttributes&) = delete;
  ChildAttributes& operator=(const ChildAttributes&) = delete;
  posix_spawnattr_t attributes;
};

pid_t WaitFor(pid_t pid, int* status) {
  pid_t done = 0;
  while ((done = ::waitpid(pid, status, 0)) < 0 && errno == EINTR) {
  }
  return done;
}

}  // namespace

absl::Status PostgresSupervisor::Run(const std::string& tool, const std::vector<std::string>& args) const {
  std::vector<std::string> argv;
  if (as_postgres_) argv = {"/usr/sbin/runuser", "-u", "postgres", "--"};
  argv.push_back((options_.bin_dir / tool).string());
  argv.insert(argv.end(), args.begin(), args.end());
  const auto output = options_.data_dir / (tool + ".out");

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, output.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  const ChildAttributes child;

  std::vector<char*> raw;
  for (auto& arg : argv) raw.push_back(arg.data());
  raw.push_back(nullptr);
  pid_t pid = 0;
  const int error = posix_spawn(&pid, raw[0], &actions, &child.attributes, raw.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (error != 0) return absl::InternalError(absl::StrCat("cannot run ", argv[0], ": ", std::strerror(error)));
  int status = 0;
  WaitFor(pid, &status);
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return absl::OkStatus();
  return absl::InternalError(absl::StrCat(tool, " ", absl::StrJoin(args, " "), " failed (status ", status,
                                          "): ", Tail(output, 600)));
}

absl::StatusOr<std::unique_ptr<PostgresSupervisor>> PostgresSupervisor::Start(Options options) {
  if (options.bin_dir.empty()) options.bin_dir = FindBinDir();
  if (options.bin_dir.empty() || !std::filesystem::exists(options.bin_dir / "pg_ctl")) {
    return absl::FailedPreconditionError(
        "no PostgreSQL server found under /usr/lib/postgresql (scripts/install-deps.sh installs it), "
        "or give --database-url");
  }
  std::error_code error;
  options.data_dir = std::filesystem::absolute(options.data_dir, error);
  std::unique_ptr<PostgresSupervisor> supervisor(new PostgresSupervisor(std::move(options)));
  const auto& data_dir = supervisor->options_.data_dir;
  const auto& run_dir = supervisor->run_dir_;
  const std::string run_text = run_dir.string();
  if (run_text.size() + std::string_view("/.s.PGSQL.5432").size() > kMaxSocketPath) {
    return absl::FailedPreconditionError(absl::StrCat("the data directory ", data_dir.string(),
                                                      " is too long for a unix socket path; choose a shorter one"));
  }
  if (run_text.find('\'') != std::string::npos) {
    return absl::FailedPreconditionError("the data directory's path must not contain a single quote");
  }
  std::filesystem::create_directories(run_dir, error);
  if (error) return absl::FailedPreconditionError(absl::StrCat("cannot create ", run_dir.string(), ": ", error.message()));
  ::chmod(data_dir.c_str(), 0755);

  if (supervisor->as_postgres_) {
    const passwd* postgres = ::getpwnam("postgres");
    if (postgres == nullptr) return absl::FailedPreconditionError("running as root, but there is no postgres user");
    for (const auto& dir : {run_dir, supervisor->cluster_dir_}) {
      std::filesystem::create_directories(dir, error);
      if (::chown(dir.c_str(), postgres->pw_uid, postgres->pw_gid) != 0) {
        return absl::FailedPreconditionError(absl::StrCat("cannot hand ", dir.string(), " to the postgres user"));
      }
    }
    ::chmod(supervisor->cluster_dir_.c_str(), 0700);
    // Every directory above must be enterable by postgres (/root is not).
    if (!supervisor->Run("pg_ctl", {"--version"}).ok() ||
        ::access(data_dir.c_str(), X_OK) != 0) {
      return absl::FailedPreconditionError("cannot run PostgreSQL's tools as the postgres user");
    }
    for (auto dir = data_dir; dir != dir.root_path(); dir = dir.parent_path()) {
      struct stat info {};
      if (::stat(dir.c_str(), &info) == 0 && (info.st_mode & S_IXOTH) == 0 && info.st_uid != postgres->pw_uid) {
        return absl::FailedPreconditionError(absl::StrCat(
            "the postgres user cannot enter ", dir.string(), ", so it cannot reach the data directory ",
            data_dir.string(), "; choose --data-dir under a directory every user can enter (e.g. /var/lib/insdiag)"));
      }
    }
  }

  INSDIAG_RETURN_IF_ERROR(supervisor->LockDataDir());
  const std::string cluster = supervisor->cluster_dir_.string();
  if (!std::filesystem::exists(supervisor->cluster_dir_ / "PG_VERSION")) {
    if (auto status = supervisor->Run("initdb", {"-D", cluster, "--no-sync", "-A", "trust", "-U", "postgres",
                                                 "-E", "UTF8", "--locale=C.UTF-8"});
        !status.ok()) {
      return status;
    }
  }
  // A cluster still running is an orphan (this server holds the data
  // directory's lock, so no other insdiagd owns it): it is stopped and
  // started again under this server's guard.
  if (supervisor->Run("pg_ctl", {"status", "-D", cluster}).ok()) {
    Log(LogLevel::kWarning, absl::StrCat("an embedded PostgreSQL left running by an earlier insdiagd in ", cluster,
                                         " is stopped and started again under this server"));
    INSDIAG_RETURN_IF_ERROR(supervisor->Run("pg_ctl", {"stop", "-w", "-t", "60", "-m", "fast", "-D", cluster}));
  }
  INSDIAG_RETURN_IF_ERROR(supervisor->StartCluster());
  supervisor->running_ = true;
  if (supervisor->options_.restart_check_interval.count() > 0) {
    supervisor->watchdog_ = std::thread([s = supervisor.get()] { s->KeepClusterRunning(); });
  }

  INSDIAG_ASSIGN_OR_RETURN(
      auto admin, kb::Connection::Open(absl::StrCat("host='", run_text, "' port=", kSocketPort,
                                                    " user=postgres dbname=postgres")));
  INSDIAG_RETURN_IF_ERROR(admin.CreateDatabaseIfMissing(supervisor->options_.database));
  return supervisor;
}

absl::Status PostgresSupervisor::LockDataDir() {
  const auto lock_path = options_.data_dir / "insdiagd.lock";
  // O_CLOEXEC: the lock is this process's alone, not its children's.
  lock_fd_ = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock_fd_ < 0) {
    return absl::FailedPreconditionError(absl::StrCat("cannot open ", lock_path.string(), ": ", std::strerror(errno)));
  }
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    return absl::FailedPreconditionError(absl::StrCat(
        "another insdiagd serves the data directory ", options_.data_dir.string(), " (it holds ", lock_path.string(),
        "): stop it first, or give this one another --data-dir"));
  }
  return absl::OkStatus();
}

absl::Status PostgresSupervisor::StartCluster() {
  const std::string settings = absl::StrCat("-c listen_addresses='' -k '", run_dir_.string(), "' -p ", kSocketPort);
  INSDIAG_RETURN_IF_ERROR(Run("pg_ctl", {"start", "-w", "-t", "60", "-D", cluster_dir_.string(), "-l",
                                         (run_dir_ / "postgresql.log").string(), "-o", settings}));
  return StartGuard();
}

absl::Status PostgresSupervisor::StartGuard() {
  StopGuard();  // of the postmaster before, which a restart replaced
  const auto pid_file = cluster_dir_ / "postmaster.pid";
  std::ifstream in(pid_file);
  pid_t postmaster = 0;
  if (!(in >> postmaster) || postmaster <= 0) {
    return absl::InternalError(absl::StrCat(pid_file.string(), " names no postmaster after pg_ctl start"));
  }
  int ends[2];
  if (::pipe2(ends, O_CLOEXEC) != 0) return absl::InternalError(absl::StrCat("pipe: ", std::strerror(errno)));
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, ends[0], STDIN_FILENO);  // dup2 clears O_CLOEXEC
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  const ChildAttributes child;
  std::vector<std::string> argv = {"/bin/sh", "-c", kGuardScript, "insdiag-postgres-guard",
                                   std::to_string(postmaster), pid_file.string()};
  std::vector<char*> raw;
  for (auto& arg : argv) raw.push_back(arg.data());
  raw.push_back(nullptr);
  const int error = posix_spawn(&guard_pid_, raw[0], &actions, &child.attributes, raw.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(ends[0]);
  if (error != 0) {
    ::close(ends[1]);
    guard_pid_ = 0;
    return absl::InternalError(absl::StrCat("cannot start the PostgreSQL guard: ", std::strerror(error)));
  }
  guard_pipe_fd_ = ends[1];
  return absl::OkStatus();
}

void PostgresSupervisor::StopGuard() {
  if (guard_pipe_fd_ >= 0) ::close(guard_pipe_fd_);  // the guard reads the end
  guard_pipe_fd_ = -1;
  if (guard_pid_ > 0) {
    int status = 0;
    WaitFor(guard_pid_, &status);
  }
  guard_pid_ = 0;
}

void PostgresSupervisor::KeepClusterRunning() {
  std::unique_lock lock(mutex_);
  // Stopped at two checks in a row: a restart by hand (pg_ctl restart) is
  // stopped for a moment only, and is not raced.
  bool stopped_before = false;
  while (!stopping_.wait_for(lock, options_.restart_check_interval, [this] { return !running_; })) {
    const bool stopped = !Run("pg_ctl", {"status", "-D", cluster_dir_.string()}).ok();
    const bool start_again = stopped && stopped_before;
    stopped_before = stopped && !start_again;
    if (!start_again) continue;
    Log(LogLevel::kWarning, absl::StrCat("the embedded PostgreSQL stopped (its log: ",
                                         (run_dir_ / "postgresql.log").string(), "); starting it again"));
    if (auto started = StartCluster(); started.ok()) {
      ++restarts_;
      Log(LogLevel::kInfo, "the embedded PostgreSQL runs again");
    } else {
      Log(LogLevel::kError, absl::StrCat("cannot start the embedded PostgreSQL again (next try in ",
                                         options_.restart_check_interval.count(), " ms): ", started.message()));
    }
  }
}

int PostgresSupervisor::restarts() const {
  std::lock_guard lock(mutex_);
  return restarts_;
}

std::string PostgresSupervisor::database_url() const {
  // Quoted values: the data directory may contain spaces (single quotes are refused).
  return absl::StrCat("host='", run_dir_.string(), "' port=", kSocketPort, " user=postgres dbname='",
                      options_.database, "'");
}

absl::Status PostgresSupervisor::Stop() {
  {
    std::lock_guard lock(mutex_);
    if (!running_) return absl::OkStatus();
    running_ = false;
  }
  stopping_.notify_all();
  if (watchdog_.joinable()) watchdog_.join();
  absl::Status stopped = Run("pg_ctl", {"stop", "-w", "-t", "60", "-m", "fast", "-D", cluster_dir_.string()});
  StopGuard();  // after the stop: the guard then finds no postmaster.pid
  return stopped;
}

PostgresSupervisor::~PostgresSupervisor() {
  (void)Stop();
  StopGuard();
  if (lock_fd_ >= 0) ::close(lock_fd_);
}

}  // namespace insdiag::server
