// insdiagd — the insdiag server. Wires the components together:
//   embedded PostgreSQL (unless --database-url) → connection pool →
//   migrations → gRPC + REST server → wait for SIGINT/SIGTERM → shut down.
#include <absl/strings/str_cat.h>
#include <signal.h>

#include <CLI/CLI.hpp>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <thread>

#include "insdiag/engine/status_macros.h"
#include "insdiag/kb/connection_pool.h"
#include "insdiag/kb/migrations.h"
#include "insdiag/server/insdiag_server.h"
#include "insdiag/server/postgres_supervisor.h"
#include "insdiag/server/server_log.h"

namespace {

int Fail(const absl::Status& status) {
  insdiag::server::Log(insdiag::server::LogLevel::kError, std::string(status.message()));
  return 1;
}

// The page: $INSDIAG_WEB_DIR, else where this build put it.
std::string DefaultWebDir() {
  const char* env = std::getenv("INSDIAG_WEB_DIR");
  return env != nullptr && *env != '\0' ? env : INSDIAG_DEFAULT_WEB_DIR;
}

std::string DefaultDataDir() {
  const char* env = std::getenv("INSDIAG_DATA_DIR");
  return env != nullptr && *env != '\0' ? env : ".insdiag";
}

bool IsLoopback(const std::string& address) {
  return address == "localhost" || address == "::1" || address.rfind("127.", 0) == 0;
}

// Everything the command line sets.
struct DaemonSettings {
  std::string data_dir = DefaultDataDir();
  std::string database_url;
  std::string read_url;
  std::string migrations_dir;
  std::string log_format = "text";
  int workers = 1;
  double lease_s = 30.0;
  // AnalysisWorkers::Options::cache_bytes in MiB.
  long analysis_cache_mb = static_cast<long>(insdiag::server::AnalysisWorkers::Options{}.cache_bytes >> 20);
  double fleet_refresh_s = 600.0;
  insdiag::server::InsdiagServer::Options options;
};

void AddOptions(CLI::App& app, DaemonSettings& s) {
  app.add_option("--data-dir", s.data_dir,
                 "Directory of the embedded PostgreSQL cluster and of the first admin token "
                 "(default $INSDIAG_DATA_DIR, else ./.insdiag)");
  app.add_option("--grpc-port", s.options.grpc_port, "gRPC port (0: any free port)")
      ->capture_default_str();
  app.add_option("--http-port", s.options.http_port, "REST/JSON port (0: any free port)")
      ->capture_default_str();
  app.add_option("--database-url", s.database_url,
                 "Use this PostgreSQL (libpq URL) instead of the embedded one")
      ->envname("INSDIAG_DATABASE_URL");
  app.add_option("--read-database-url", s.read_url,
                 "Read the fleet statistics and the listings from this PostgreSQL (libpq URL): a "
                 "streaming replica "
                 "of the database")
      ->envname("INSDIAG_READ_DATABASE_URL");
  app.add_option(
         "--bind", s.options.bind_address,
         "Address to listen on (loopback by default; elsewhere, tokens cross the network in clear)")
      ->capture_default_str();
  app.add_option("--tls-cert", s.options.tls_cert_file,
                 "PEM certificate chain: serve gRPC and HTTPS over TLS");
  app.add_option("--tls-key", s.options.tls_key_file, "PEM private key of --tls-cert");
  app.add_option("--migrations-dir", s.migrations_dir,
                 "Apply migrations from this directory instead of those built in");
  s.options.web_dir = DefaultWebDir();
  app.add_option("--web-dir", s.options.web_dir,
                 "Serve the page from this directory (default $INSDIAG_WEB_DIR, else the build's)")
      ->capture_default_str();
  const unsigned cores = std::thread::hardware_concurrency();
  s.workers = cores > 1 ? static_cast<int>(cores) - 1 : 1;
  app.add_option("--workers", s.workers,
                 "Analysis worker threads (0: serve the API only; default: cores - 1, at least 1)")
      ->capture_default_str();
  app.add_option("--analysis-cache-mb", s.analysis_cache_mb,
                 "Memory the workers keep analysed runs in for the next analysis of the same run (an Add from "
                 "the page then re-runs model B alone; 0: keep nothing)")
      ->check(CLI::Range(0L, 1L << 24))  // up to 16 TiB: MiB that fit in bytes
      ->capture_default_str();
  app.add_option("--lease-seconds", s.lease_s,
                 "Lease of a running analysis; a job whose worker died is taken up again after it")
      ->capture_default_str();
  app.add_option("--fleet-refresh-seconds", s.fleet_refresh_s,
                 "How often the fleet statistics' materialised views are refreshed (0: never)")
      ->capture_default_str();
  app.add_option("--log-format", s.log_format,
                 "The log on stderr: text, or json (one object a line: time, level, message)")
      ->check(CLI::IsMember({"text", "json"}))
      ->envname("INSDIAG_LOG_FORMAT")
      ->capture_default_str();
}

// The workers' and the fleet views' settings from the command line's; false when one is out of range.
bool SetWorkerOptions(DaemonSettings& s) {
  if (s.workers < 0 || s.lease_s <= 0 || s.fleet_refresh_s < 0 || s.analysis_cache_mb < 0) return false;
  s.options.workers.workers = s.workers;
  s.options.workers.cache_bytes = static_cast<std::size_t>(s.analysis_cache_mb) << 20;
  s.options.workers.lease = std::chrono::milliseconds(static_cast<long>(s.lease_s * 1000));
  s.options.fleet_refresh = std::chrono::milliseconds(static_cast<long>(s.fleet_refresh_s * 1000));
  return true;
}

absl::Status MigrateSchema(insdiag::kb::ConnectionPool& pool, const std::string& migrations_dir) {
  std::vector<insdiag::kb::Migration> from_dir;
  if (!migrations_dir.empty()) {
    INSDIAG_ASSIGN_OR_RETURN(auto loaded, insdiag::kb::LoadMigrationsFromDirectory(migrations_dir));
    from_dir = std::move(loaded);
  }
  INSDIAG_ASSIGN_OR_RETURN(auto lease, pool.Acquire());
  INSDIAG_ASSIGN_OR_RETURN(
      auto applied, insdiag::kb::ApplyMigrations(*lease, migrations_dir.empty()
                                                              ? insdiag::kb::EmbeddedMigrations()
                                                              : std::span(from_dir)));
  insdiag::server::Log(
      insdiag::server::LogLevel::kInfo,
      absl::StrCat("schema up to date (", applied.applied, " migrations applied now, ",
                   applied.already_applied, " before)"));
  return absl::OkStatus();
}

// What a user starting the server needs to know: where it listens, where the
// first admin token and the page are, and whether tokens cross in clear.
void AnnounceListening(const insdiag::server::InsdiagServer& server, const DaemonSettings& s,
                       const insdiag::server::PostgresSupervisor* postgres,
                       bool reads_from_replica) {
  using insdiag::server::Log;
  using insdiag::server::LogLevel;
  const auto& options = s.options;
  if (server.wrote_first_admin_token()) {
    Log(LogLevel::kInfo,
        absl::StrCat("first start: an admin token is in ", options.first_admin_token_file.string(),
                     " (readable by this user only); make tokens for people and scripts with "
                     "'insdiag tokens create', then keep that file safe or delete it"));
  }
  if (!IsLoopback(options.bind_address) && options.tls_cert_file.empty()) {
    Log(LogLevel::kWarning,
        absl::StrCat("listening on ", options.bind_address,
                     " without TLS: bearer tokens and bench data cross the network in clear text"));
  }
  std::cout << "insdiagd: listening grpc=" << options.bind_address << ":" << server.grpc_port()
            << " http=" << options.bind_address << ":" << server.http_port() << " database="
            << (postgres != nullptr ? "embedded:" + postgres->cluster_dir().string()
                                    : std::string("external"))
            << " reads=" << (reads_from_replica ? "replica" : "primary") << " workers=" << s.workers
            << " tls=" << (options.tls_cert_file.empty() ? "off" : "on") << std::endl;
  const char* scheme = options.tls_cert_file.empty() ? "http" : "https";
  if (server.serves_page()) {
    Log(LogLevel::kInfo, absl::StrCat("the page is at ", scheme, "://localhost:",
                                      server.http_port(), "/ (from ", options.web_dir, ")"));
  } else {
    Log(LogLevel::kWarning,
        absl::StrCat(
            "no page in '", options.web_dir,
            "' (scripts/install-deps.sh && scripts/build.sh build it); the REST API is served"));
  }
}

}  // namespace

int main(int argc, char** argv) {
  using insdiag::server::Log;
  using insdiag::server::LogLevel;
  CLI::App app{"insdiagd — diagnosis server for inertial navigation systems in bench tests"};
  DaemonSettings settings;
  AddOptions(app, settings);
  CLI11_PARSE(app, argc, argv);
  insdiag::server::SetLogFormat(settings.log_format == "json" ? insdiag::server::LogFormat::kJson
                                                              : insdiag::server::LogFormat::kText);
  if (!SetWorkerOptions(settings)) {
    Log(LogLevel::kError,
        "--workers, --lease-seconds, --fleet-refresh-seconds and --analysis-cache-mb must not be negative");
    return 2;
  }
  auto& options = settings.options;

  // SIGINT/SIGTERM are taken synchronously by sigwait below, after start-up;
  // blocked before any thread exists so that every thread inherits the mask.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);

  std::unique_ptr<insdiag::server::PostgresSupervisor> postgres;
  std::string database_url = settings.database_url;
  if (database_url.empty()) {
    auto started = insdiag::server::PostgresSupervisor::Start(
        {.data_dir = settings.data_dir, .bin_dir = {}, .database = "insdiag"});
    if (!started.ok()) return Fail(started.status());
    postgres = std::move(*started);
    database_url = postgres->database_url();
  }

  auto pool = insdiag::kb::ConnectionPool::Create({.database_url = database_url, .max_connections = 16});
  if (!pool.ok()) return Fail(pool.status());
  if (absl::Status migrated = MigrateSchema(**pool, settings.migrations_dir); !migrated.ok())
    return Fail(migrated);

  std::unique_ptr<insdiag::kb::ConnectionPool> read_pool;
  if (!settings.read_url.empty()) {
    auto replica = insdiag::kb::ConnectionPool::Create(
        {.database_url = settings.read_url, .max_connections = 16});
    if (!replica.ok()) return Fail(replica.status());
    read_pool = std::move(*replica);
    options.read_pool = read_pool.get();
  }

  options.first_admin_token_file =
      std::filesystem::absolute(std::filesystem::path(settings.data_dir) / "admin-token");
  auto server = insdiag::server::InsdiagServer::Start(**pool, options);
  if (!server.ok()) return Fail(server.status());
  AnnounceListening(**server, settings, postgres.get(), read_pool != nullptr);

  int signal_number = 0;
  sigwait(&stop_signals, &signal_number);
  Log(LogLevel::kInfo, absl::StrCat(signal_number == SIGINT ? "SIGINT" : "SIGTERM", ", shutting down"));
  (*server)->Shutdown();
  server->reset();
  pool->reset();
  if (postgres) {
    if (auto stopped = postgres->Stop(); !stopped.ok()) return Fail(stopped);
  }
  return 0;
}
