// The insdiag server: the gRPC services (with health checking and
// reflection) on one port and their REST/JSON face on another, over a
// PostgreSQL connection pool, both over TLS when given a certificate.
// Start() returns once both listen.
#pragma once

#include <absl/status/statusor.h>

#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "insdiag/kb/connection_pool.h"
#include "insdiag/server/analysis_workers.h"
#include "insdiag/server/rest_route.h"

namespace grpc {
class Server;
}  // namespace grpc
namespace httplib {
class Server;
}  // namespace httplib

namespace insdiag::server {

class RestGateway;
class RunService;
class RunServiceGrpc;

class InsdiagServer {
 public:
  struct Options {
    // Loopback unless told otherwise: without TLS, tokens cross the network in clear.
    std::string bind_address = "127.0.0.1";
    int grpc_port = 50051;  // 0: any free port (see grpc_port())
    int http_port = 8080;   // 0: any free port (see http_port())
    std::size_t max_upload_samples = 20'000'000;
    // The analysis worker pool (analysis_workers.h): workers, lease, poll.
    AnalysisWorkers::Options workers;
    // How often the fleet statistics' materialised views are refreshed
    // (fleet_view_refresher.h); 0: never.
    std::chrono::milliseconds fleet_refresh{600'000};
    std::chrono::milliseconds watch_poll{250};
    // Upsert the built-in unit types and failure modes at start.
    bool seed_knowledge_base = true;
    // The page's files (web_page.h); empty: no page.
    std::string web_dir;
    // On a database without any token, an ADMIN token is made and its secret
    // written here (mode 0600); empty: none is made.
    std::filesystem::path first_admin_token_file;
    // PEM certificate chain and private key: both set, gRPC and HTTP serve
    // TLS only; both empty, neither does.
    std::string tls_cert_file;
    std::string tls_key_file;
    // How often the health service asks the database whether it answers:
    // a server whose database is down says NOT_SERVING (gRPC health, /healthz).
    std::chrono::milliseconds health_poll{1000};
    // Where the fleet statistics and the listings (runs, analyses, units,
    // modules, diagnoses, failure records, unit types, failure modes) are
    // read: a PostgreSQL streaming replica of the database, for reads one
    // server cannot carry. Null: the primary. Writes, single reads, tokens,
    // the audit trail and job claims stay on the primary. A replica lags by
    // its replay delay: a listing may miss a write of the last moment.
    kb::ConnectionPool* read_pool = nullptr;
  };

  // `pool` (and `read_pool`) must outlive the server. UNAVAILABLE when
  // a port cannot be bound.
  static absl::StatusOr<std::unique_ptr<InsdiagServer>> Start(kb::ConnectionPool& pool, Options options);
  ~InsdiagServer();  // Shutdown()

  // The services it serves, full names ("insdiag.v1.RunService"): every
  // method of each carries an access rule, and its http rules are the REST face.
  static const std::vector<std::string>& ServiceNames();

  int grpc_port() const { return grpc_port_; }
  // Every route the REST face serves (rest_gateway.h).
  std::vector<RestRoute> rest_routes() const;
  int http_port() const { return http_port_; }
  // Whether this start made the first ADMIN token (Options::first_admin_token_file).
  bool wrote_first_admin_token() const { return wrote_first_admin_token_; }
  // Whether GET / serves the page (Options::web_dir holds index.html).
  bool serves_page() const { return serves_page_; }

  // Stops accepting, lets running calls finish (at most a few seconds),
  // then stops. Idempotent; safe from any thread.
  void Shutdown();

 private:
  InsdiagServer();
  // Start's steps, in order: the gRPC server, then the REST gateway and the
  // page over HTTP(S) (through gRPC in process), then the database's health.
  absl::Status StartGrpc(const Options& options);
  absl::Status StartHttp(const Options& options);
  void StartHealthWatch(kb::ConnectionPool& pool, std::chrono::milliseconds poll);
  struct Services;
  std::unique_ptr<Services> services_;
  std::unique_ptr<grpc::Server> grpc_;
  std::unique_ptr<RestGateway> gateway_;
  std::unique_ptr<httplib::Server> http_;
  std::thread http_thread_;
  std::thread health_thread_;
  std::mutex health_mutex_;
  std::condition_variable health_wake_;
  bool stopping_ = false;
  int grpc_port_ = 0;
  int http_port_ = 0;
  bool serves_page_ = false;
  bool wrote_first_admin_token_ = false;
  std::once_flag shutdown_once_;
};

}  // namespace insdiag::server
