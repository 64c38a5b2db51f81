#include "support/insdiagd_process.h"

#include <absl/strings/str_cat.h>

#include <fstream>
#include <regex>
#include <thread>

namespace insdiag::testing {

absl::StatusOr<RunningInsdiagd> StartInsdiagd(const std::string& insdiagd_path, const std::string& database_url,
                                              const std::filesystem::path& dir) {
  using namespace std::chrono_literals;
  std::filesystem::create_directories(dir / "server");
  auto server = Subprocess::Start({insdiagd_path, "--database-url", database_url, "--data-dir",
                                   (dir / "server" / "data").string(), "--grpc-port", "0", "--http-port", "0",
                                   "--bind", "127.0.0.1", "--workers", "1", "--fleet-refresh-seconds", "0"},
                                  dir / "server");
  if (!server.ok()) return server.status();
  RunningInsdiagd running;
  running.process = std::make_unique<Subprocess>(std::move(*server));
  const std::regex listening(R"(listening grpc=[^ ]*:(\d+) http=[^ ]*:(\d+))");
  for (int i = 0; i < 400 && running.grpc_address.empty(); ++i) {
    std::smatch match;
    const std::string out = running.process->Stdout();
    if (std::regex_search(out, match, listening)) {
      running.grpc_address = "127.0.0.1:" + match[1].str();
      running.http_port = std::stoi(match[2].str());
    }
    std::this_thread::sleep_for(25ms);
  }
  if (running.grpc_address.empty()) {
    return absl::UnavailableError(absl::StrCat("insdiagd did not listen: ", running.process->Stderr()));
  }
  std::ifstream(dir / "server" / "data" / "admin-token") >> running.admin_token;
  if (running.admin_token.empty()) {
    return absl::UnavailableError(absl::StrCat("insdiagd wrote no admin token: ", running.process->Stderr()));
  }
  return running;
}

}  // namespace insdiag::testing
