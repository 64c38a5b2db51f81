// The real insdiagd for end-to-end tests: started on a database the test
// owns, on ephemeral ports of 127.0.0.1 with one analysis worker, and
// found ready by its "listening" line.
#pragma once

#include <absl/status/statusor.h>

#include <filesystem>
#include <memory>
#include <string>

#include "support/subprocess.h"

namespace insdiag::testing {

struct RunningInsdiagd {
  std::unique_ptr<Subprocess> process;
  std::string grpc_address;  // "127.0.0.1:N"
  int http_port = 0;
  std::string admin_token;   // written by its first start on the database
};

// Its data directory and output go under `dir`/server. UNAVAILABLE, with
// the server's stderr, when it does not listen within 10 s.
absl::StatusOr<RunningInsdiagd> StartInsdiagd(const std::string& insdiagd_path, const std::string& database_url,
                                              const std::filesystem::path& dir);

}  // namespace insdiag::testing
