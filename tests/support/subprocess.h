// A child process for end-to-end tests: started with posix_spawn (no shell),
// its stdout and stderr captured to files, killed on destruction.
#pragma once

#include <absl/status/statusor.h>
#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace insdiag::testing {

class Subprocess {
 public:
  // Starts `argv[0]` with `argv`, the current environment plus `extra_env`
  // ("KEY=value"); output goes to files under `output_dir`.
  static absl::StatusOr<Subprocess> Start(const std::vector<std::string>& argv,
                                          const std::filesystem::path& output_dir,
                                          const std::vector<std::string>& extra_env = {});
  Subprocess(Subprocess&& other) noexcept;
  Subprocess& operator=(Subprocess&&) = delete;
  ~Subprocess();

  pid_t pid() const { return pid_; }
  void Signal(int signal) const;
  // The exit status (or 128 + signal) once the process ended within
  // `timeout`; nullopt while it still runs.
  std::optional<int> Wait(std::chrono::milliseconds timeout);
  std::string Stdout() const;
  std::string Stderr() const;

 private:
  Subprocess(pid_t pid, std::filesystem::path out, std::filesystem::path err)
      : pid_(pid), stdout_path_(std::move(out)), stderr_path_(std::move(err)) {}
  pid_t pid_;
  std::optional<int> exit_status_;
  std::filesystem::path stdout_path_;
  std::filesystem::path stderr_path_;
};

// Runs a program to completion (at most `timeout`) and returns its exit
// status; stdout/stderr into `stdout_text`/`stderr_text`.
struct Completed {
  int exit_status = -1;
  std::string stdout_text;
  std::string stderr_text;
};
absl::StatusOr<Completed> RunToCompletion(const std::vector<std::string>& argv,
                                          const std::filesystem::path& output_dir,
                                          std::chrono::milliseconds timeout,
                                          const std::vector<std::string>& extra_env = {});

// The whole file, byte for byte; empty when it cannot be read.
std::string ReadFile(const std::filesystem::path& path);

// A fresh directory under the system temp dir, readable by other users (an
// embedded PostgreSQL runs as `postgres` when the tests run as root).
std::filesystem::path MakeTempDir(const std::string& prefix);

}  // namespace insdiag::testing
