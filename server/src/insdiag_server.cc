#include "insdiag/server/insdiag_server.h"

#include <absl/strings/str_cat.h>
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>

#include <chrono>

#include "insdiag/kb/run_store.h"
#include "insdiag/server/grpc_services.h"
#include "insdiag/server/rest_gateway.h"
#include "insdiag/server/run_service.h"
#include "insdiag/v1/analyses.grpc.pb.h"
#include "insdiag/v1/fleet.grpc.pb.h"
#include "insdiag/v1/knowledge.grpc.pb.h"

// Last: httplib.h pulls in <resolv.h>, whose `_res` macro breaks Eigen's headers.
#include <httplib.h>

namespace insdiag::server {

// What the gRPC server serves. Analyses, the knowledge base and fleet
// statistics are the generated bases for now: every method answers
// UNIMPLEMENTED, on both faces.
struct InsdiagServer::Services {
  Services(kb::ConnectionPool& pool, const Options& options)
      : store(pool), runs(store, RunService::Options{options.max_upload_samples}), runs_grpc(runs) {}
  kb::RunStore store;
  RunService runs;
  RunServiceGrpc runs_grpc;
  v1::AnalysisService::Service analyses;
  v1::KnowledgeService::Service knowledge;
  v1::FleetService::Service fleet;
};

InsdiagServer::InsdiagServer() = default;

absl::StatusOr<std::unique_ptr<InsdiagServer>> InsdiagServer::Start(kb::ConnectionPool& pool, Options options) {
  std::unique_ptr<InsdiagServer> server(new InsdiagServer());
  server->services_ = std::make_unique<Services>(pool, options);

  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  builder.AddListeningPort(absl::StrCat(options.bind_address, ":", options.grpc_port),
                           grpc::InsecureServerCredentials(), &server->grpc_port_);
  builder.RegisterService(&server->services_->runs_grpc);
  builder.RegisterService(&server->services_->analyses);
  builder.RegisterService(&server->services_->knowledge);
  builder.RegisterService(&server->services_->fleet);
  server->grpc_ = builder.BuildAndStart();
  if (!server->grpc_ || server->grpc_port_ == 0) {
    return absl::UnavailableError(absl::StrCat("cannot serve gRPC on ", options.bind_address, ":", options.grpc_port));
  }

  auto gateway = RestGateway::Create(
      server->grpc_->InProcessChannel(grpc::ChannelArguments()),
      {"insdiag.v1.RunService", "insdiag.v1.AnalysisService", "insdiag.v1.KnowledgeService", "insdiag.v1.FleetService"});
  if (!gateway.ok()) return gateway.status();
  server->gateway_ = std::move(*gateway);
  server->http_ = std::make_unique<httplib::Server>();
  server->gateway_->Register(*server->http_);
  // A 1-hour 50 Hz run is ~20 MB of CSV; give slow links time.
  server->http_->set_read_timeout(std::chrono::seconds(60));
  server->http_port_ = options.http_port == 0 ? server->http_->bind_to_any_port(options.bind_address)
                                              : (server->http_->bind_to_port(options.bind_address, options.http_port)
                                                     ? options.http_port
                                                     : -1);
  if (server->http_port_ <= 0) {
    server->http_port_ = 0;
    return absl::UnavailableError(absl::StrCat("cannot serve HTTP on ", options.bind_address, ":", options.http_port));
  }
  server->http_thread_ = std::thread([http = server->http_.get()] { http->listen_after_bind(); });
  return server;
}

void InsdiagServer::Shutdown() {
  std::call_once(shutdown_once_, [this] {
    // HTTP first: its handlers call into the gRPC server.
    if (http_) {
      // stop() only stops a server that already listens: give the listening
      // thread a moment to get there if Shutdown() follows Start() at once.
      for (int waited_ms = 0; !http_->is_running() && waited_ms < 2000; ++waited_ms) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
      http_->stop();
    }
    if (http_thread_.joinable()) http_thread_.join();
    if (grpc_) grpc_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(5));
  });
}

InsdiagServer::~InsdiagServer() { Shutdown(); }

}  // namespace insdiag::server
