#include "insdiag/server/insdiag_server.h"

#include <absl/strings/ascii.h>
#include <absl/strings/match.h>
#include <absl/strings/str_cat.h>
#include <absl/strings/str_join.h>
#include <absl/strings/str_split.h>
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>

#include <atomic>
#include <chrono>
#include <fstream>
#include <sstream>

#include "insdiag/engine/status_macros.h"
#include "insdiag/kb/catalogue_data.h"
#include "insdiag/kb/knowledge_messages.h"
#include "insdiag/kb/run_store.h"
#include "insdiag/server/access_guard.h"
#include "insdiag/server/analysis_workers.h"
#include "insdiag/server/fleet_view_refresher.h"
#include "insdiag/server/grpc_services.h"
#include "insdiag/server/metrics.h"
#include "insdiag/server/rest_gateway.h"
#include "insdiag/server/run_service.h"
#include "insdiag/server/status_mapping.h"
#include "insdiag/server/web_page.h"
#include "analysis_codec.h"
#include "request_edge.h"
#include "insdiag/v1/analyses.grpc.pb.h"
#include "insdiag/v1/fleet.grpc.pb.h"
#include "insdiag/v1/knowledge.grpc.pb.h"

// Last: httplib.h pulls in <resolv.h>, whose `_res` macro breaks Eigen's headers.
#include <httplib.h>

namespace insdiag::server {

// What the gRPC server serves, the analysis workers and the fleet views' refresh.
struct InsdiagServer::Services {
  Services(kb::ConnectionPool& pool, const Options& options)
      : connection_pool(pool), access_store(pool), guard(access_store), access(access_store), access_grpc(access, guard), store(pool, options.read_pool),
        runs(store, RunService::Options{options.max_upload_samples}), runs_grpc(runs, guard), analysis_store(pool, options.read_pool),
        // Wakes `workers`, built after it: only RPC handlers queue jobs, and
        // the servers drain them before these services are destroyed.
        analyses(analysis_store, AnalysisService::Options{options.watch_poll, [this] { workers.Wake(); }}),
        catalogue_store(pool, options.read_pool), failure_record_store(pool, kb::DecodeReportFindings, options.read_pool),
        diagnosis_store(pool, kb::DecodeReportFindings, options.read_pool), unit_history_store(pool, options.read_pool),
        knowledge(catalogue_store, failure_record_store, diagnosis_store, unit_history_store), knowledge_grpc(knowledge, guard),
        test_reports(analyses, runs, knowledge, TestReportService::Options{}), analyses_grpc(analyses, test_reports, guard, stopping),
        fleet_store(options.read_pool != nullptr ? *options.read_pool : pool), fleet_grpc(fleet_store, guard),
        live(runs, analyses, pool, LiveRunService::Options{}), live_grpc(live, guard, stopping), workers(pool, options.workers, &metrics),
        fleet_refresher(pool, options.fleet_refresh) {}
  // What GET /metrics answers: the counters, then the queue and the pool as they are.
  std::string RenderMetrics() {
    Metrics::Gauges gauges;
    if (auto queue = analysis_store.Queue(); queue.ok()) {
      gauges.queue_known = true;
      gauges.queued = queue->queued;
      gauges.running = queue->running;
      gauges.oldest_queued_age_s = queue->oldest_queued_age_s;
    }
    const kb::ConnectionPool::Usage usage = connection_pool.usage();
    gauges.pool_open = usage.open;
    gauges.pool_idle = usage.idle;
    gauges.pool_max = usage.max;
    const engine::AnalysisCache::Counts cache = workers.cache_counts();
    gauges.analysis_cache_bytes = workers.cache_bytes();
    gauges.preparations_made = cache.preparations_made;
    gauges.preparations_reused = cache.preparations_reused;
    gauges.screenings_reused = cache.screenings_reused;
    gauges.models_a_kept = cache.models_a_kept;
    gauges.models_a_reused = cache.models_a_reused;
    return metrics.Render(gauges);
  }
  kb::ConnectionPool& connection_pool;
  std::atomic<bool> stopping{false};  // ends the watching streams (grpc_services.h); before the services
  Metrics metrics;  // before `workers`, which count into it
  kb::AccessStore access_store;
  AccessGuard guard;
  AccessService access;
  AccessServiceGrpc access_grpc;
  kb::RunStore store;
  RunService runs;
  RunServiceGrpc runs_grpc;
  kb::AnalysisStore analysis_store;
  AnalysisService analyses;
  kb::CatalogueStore catalogue_store;
  kb::FailureRecordStore failure_record_store;
  kb::DiagnosisStore diagnosis_store;
  kb::UnitHistoryStore unit_history_store;
  KnowledgeService knowledge;
  KnowledgeServiceGrpc knowledge_grpc;
  TestReportService test_reports;  // reads through runs, analyses and knowledge
  AnalysisServiceGrpc analyses_grpc;
  kb::FleetStore fleet_store;
  FleetServiceGrpc fleet_grpc;
  LiveRunService live;
  LiveRunServiceGrpc live_grpc;
  AnalysisWorkers workers;
  FleetViewRefresher fleet_refresher;  // on the primary: a replica cannot refresh
};

InsdiagServer::InsdiagServer() = default;

const std::vector<std::string>& InsdiagServer::ServiceNames() {
  static const std::vector<std::string> names = {
      "insdiag.v1.RunService",   "insdiag.v1.AnalysisService", "insdiag.v1.KnowledgeService",
      "insdiag.v1.FleetService", "insdiag.v1.AccessService",   "insdiag.v1.LiveRunService"};
  return names;
}

std::vector<RestRoute> InsdiagServer::rest_routes() const { return gateway_->routes(); }

namespace {

absl::StatusOr<std::string> ReadPemFile(const std::string& path, const char* flag) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  if (!in || !(text << in.rdbuf())) return absl::InvalidArgumentError(absl::StrCat(flag, " ", path, ": cannot read"));
  if (!absl::StrContains(text.str(), "-----BEGIN ")) {
    return absl::InvalidArgumentError(absl::StrCat(flag, " ", path, ": not a PEM file"));
  }
  return text.str();
}

// The server's certificate chain and private key, both required.
absl::StatusOr<grpc::SslServerCredentialsOptions::PemKeyCertPair> ReadKeyCertPair(
    const InsdiagServer::Options& options) {
  if (options.tls_cert_file.empty() || options.tls_key_file.empty()) {
    return absl::InvalidArgumentError("TLS needs both --tls-cert and --tls-key");
  }
  INSDIAG_ASSIGN_OR_RETURN(auto cert, ReadPemFile(options.tls_cert_file, "--tls-cert"));
  INSDIAG_ASSIGN_OR_RETURN(auto key, ReadPemFile(options.tls_key_file, "--tls-key"));
  return grpc::SslServerCredentialsOptions::PemKeyCertPair{key, cert};
}

// Counts each request's duration for the metrics, and keeps brotli out of
// what a client accepts. Browsers accept "gzip, deflate, br, zstd", and
// Debian's compiled cpp-httplib then answers with brotli at its default
// quality 11: seconds of CPU for a few hundred kB of JSON or JavaScript, where
// gzip takes milliseconds. (The request is httplib's own non-const object,
// handed over as const.) httplib runs the pre-routing handler and the logger
// on the request's own thread.
void InstrumentHttp(httplib::Server& http, Metrics& metrics) {
  static thread_local std::chrono::steady_clock::time_point request_start;
  http.set_logger([metrics = &metrics](const httplib::Request& request,
                                       const httplib::Response& response) {
    const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - request_start;
    metrics->CountHttpRequest(request.method, response.status, elapsed.count());
  });
  http.set_pre_routing_handler([](const httplib::Request& request, httplib::Response&) {
    request_start = std::chrono::steady_clock::now();
    auto& headers = const_cast<httplib::Request&>(request).headers;
    for (auto& [name, value] : headers) {
      if (!absl::EqualsIgnoreCase(name, "Accept-Encoding") || !absl::StrContains(value, "br"))
        continue;
      std::vector<std::string> kept;
      for (absl::string_view coding : absl::StrSplit(value, ',')) {
        coding = absl::StripAsciiWhitespace(coding);
        if (!absl::StartsWith(coding, "br")) kept.emplace_back(coding);
      }
      value = absl::StrJoin(kept, ", ");
    }
    return httplib::Server::HandlerResponse::Unhandled;
  });
}

bool UsesTls(const InsdiagServer::Options& options) {
  return !options.tls_cert_file.empty() || !options.tls_key_file.empty();
}

}  // namespace

absl::StatusOr<std::unique_ptr<InsdiagServer>> InsdiagServer::Start(kb::ConnectionPool& pool, Options options) {
  std::unique_ptr<InsdiagServer> server(new InsdiagServer());
  server->services_ = std::make_unique<Services>(pool, options);
  if (options.seed_knowledge_base) {
    // The built-in unit types and failure modes, upserted idempotently.
    INSDIAG_RETURN_IF_ERROR(kb::SeedBuiltinCatalogues(server->services_->catalogue_store));
  }

  if (auto guarded = AccessGuard::CheckEveryMethodHasARule(ServiceNames()); !guarded.ok())
    return guarded;
  if (!options.first_admin_token_file.empty()) {
    INSDIAG_ASSIGN_OR_RETURN(auto made, server->services_->access_store.CreateFirstAdminToken(
                                            options.first_admin_token_file));
    server->wrote_first_admin_token_ = made;
  }
  INSDIAG_RETURN_IF_ERROR(server->StartGrpc(options));
  INSDIAG_RETURN_IF_ERROR(server->StartHttp(options));
  server->StartHealthWatch(pool, options.health_poll);
  server->services_->workers.Start();
  server->services_->fleet_refresher.Start();
  return server;
}

absl::Status InsdiagServer::StartGrpc(const Options& options) {
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  std::shared_ptr<grpc::ServerCredentials> credentials = grpc::InsecureServerCredentials();
  if (UsesTls(options)) {
    INSDIAG_ASSIGN_OR_RETURN(auto pair, ReadKeyCertPair(options));
    grpc::SslServerCredentialsOptions ssl;
    ssl.pem_key_cert_pairs.push_back(pair);
    credentials = grpc::SslServerCredentials(ssl);
  }
  builder.AddListeningPort(absl::StrCat(options.bind_address, ":", options.grpc_port), credentials,
                           &grpc_port_);
  std::vector<std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>> interceptors;
  interceptors.push_back(MetricsInterceptorFactory(services_->metrics));
  builder.experimental().SetInterceptorCreators(std::move(interceptors));
  builder.RegisterService(&services_->runs_grpc);
  builder.RegisterService(&services_->analyses_grpc);
  builder.RegisterService(&services_->knowledge_grpc);
  builder.RegisterService(&services_->fleet_grpc);
  builder.RegisterService(&services_->access_grpc);
  builder.RegisterService(&services_->live_grpc);
  grpc_ = builder.BuildAndStart();
  if (!grpc_ || grpc_port_ == 0) {
    return absl::UnavailableError(absl::StrCat("cannot serve gRPC on ", options.bind_address, ":", options.grpc_port));
  }
  return absl::OkStatus();
}

absl::Status InsdiagServer::StartHttp(const Options& options) {
  // The gateway takes whatever the services answer: an answer must not be
  // refused for its size on the way (gRPC's default limit is 4 MiB, -1 is
  // none). The services bound what they answer (a listing carries
  // summaries, docs/API.md "Limits").
  grpc::ChannelArguments in_process;
  in_process.SetMaxReceiveMessageSize(-1);
  INSDIAG_ASSIGN_OR_RETURN(auto gateway,
                           RestGateway::Create(grpc_->InProcessChannel(in_process),
                                               ServiceNames(), services_->guard.gateway_key()));
  gateway_ = std::move(gateway);
  gateway_->ServeMetrics([services = services_.get()] { return services->RenderMetrics(); });
  if (UsesTls(options)) {
    auto https = std::make_unique<httplib::SSLServer>(options.tls_cert_file.c_str(), options.tls_key_file.c_str());
    if (!https->is_valid()) {
      return absl::InvalidArgumentError(absl::StrCat("--tls-cert ", options.tls_cert_file, ", --tls-key ",
                                                     options.tls_key_file, ": HTTPS cannot use them"));
    }
    http_ = std::move(https);
  } else {
    http_ = std::make_unique<httplib::Server>();
  }
  // The page's files first: the gateway's routes take every path.
  serves_page_ = ServeWebPage(*http_, options.web_dir);
  gateway_->Register(*http_);
  // A thread serves one connection for as long as the client keeps it open: a
  // browser keeps up to six per page, and a watched analysis holds one while
  // it runs. httplib's default (a thread per core, at least 8) would queue a
  // page's requests behind idle keep-alive connections for seconds.
  http_->new_task_queue = [] { return new httplib::ThreadPool(64); };
  InstrumentHttp(*http_, services_->metrics);
  // A 1-hour 50 Hz run is ~20 MB of CSV; give slow links time.
  http_->set_read_timeout(std::chrono::seconds(60));
  http_->set_payload_max_length(kMaxRequestBodyBytes);
  // A request cpp-httplib refuses itself (a header line too long, a body too
  // large) is answered with its empty body: say which rule it broke.
  http_->set_error_handler(httplib::Server::HandlerWithResponse([](const httplib::Request&,
                                                                   httplib::Response& response) {
    if (!response.body.empty() || response.status == 404) return httplib::Server::HandlerResponse::Unhandled;
    const HttpError error = ToHttpError(
        grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, UnreadableRequestMessage(response.status)));
    response.set_content(error.json_body, "application/json");
    return httplib::Server::HandlerResponse::Handled;
  }));
  http_port_ =
      options.http_port == 0
          ? http_->bind_to_any_port(options.bind_address)
          : (http_->bind_to_port(options.bind_address, options.http_port) ? options.http_port : -1);
  if (http_port_ <= 0) {
    http_port_ = 0;
    return absl::UnavailableError(absl::StrCat("cannot serve HTTP on ", options.bind_address, ":", options.http_port));
  }
  http_thread_ = std::thread([http = http_.get()] { http->listen_after_bind(); });
  return absl::OkStatus();
}

// The health service answers for the database too: a load balancer must not
// send uploads to a server that can store nothing.
void InsdiagServer::StartHealthWatch(kb::ConnectionPool& pool, std::chrono::milliseconds poll) {
  health_thread_ = std::thread([this, &pool, poll] {
    auto* health = grpc_->GetHealthCheckService();
    std::unique_lock lock(health_mutex_);
    while (!stopping_) {
      lock.unlock();
      bool answers = false;
      if (auto db = pool.Acquire(); db.ok()) answers = (*db)->Ping().ok();
      health->SetServingStatus(answers);
      lock.lock();
      health_wake_.wait_for(lock, poll, [this] { return stopping_; });
    }
  });
}

void InsdiagServer::Shutdown() {
  std::call_once(shutdown_once_, [this] {
    {
      std::lock_guard lock(health_mutex_);
      stopping_ = true;
    }
    health_wake_.notify_all();
    if (health_thread_.joinable()) health_thread_.join();
    // Workers first: they finish the analysis they run, then stop claiming.
    // The watches end, or they would wait for what no worker will finish.
    if (services_) {
      services_->stopping = true;
      services_->workers.Stop();
      services_->fleet_refresher.Stop();
    }
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
