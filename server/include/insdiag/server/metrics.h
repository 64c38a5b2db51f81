// What operations watch, in the Prometheus text exposition format (0.0.4):
// calls by method and status with their latency, HTTP requests by method and
// status with their latency, analyses by outcome with their duration, and,
// read when scraped, the job queue, the database pool and the workers'
// analysis cache.
//
// Served at GET /metrics (rest_gateway.h) to any valid token: a scraper
// holds a VIEWER token (Prometheus: `authorization: {credentials: …}`).
#pragma once

#include <grpcpp/support/server_interceptor.h>

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <utility>

namespace insdiag::server {

class Metrics {
 public:
  // A gRPC call ("/insdiag.v1.RunService/GetRun") ended with `code` ("OK", "NOT_FOUND").
  void CountCall(std::string_view method, std::string_view code, double seconds);
  // An HTTP request ended with `status`.
  void CountHttpRequest(std::string_view method, int status, double seconds);
  // An analysis job's attempt ended: "succeeded", "failed", "retried" (queued
  // again), "cancelled" or "lost".
  void CountAnalysis(std::string_view outcome, double seconds);

  // What is read when scraped.
  struct Gauges {
    bool queue_known = false;  // false: the database did not answer
    std::int64_t queued = 0;
    std::int64_t running = 0;
    double oldest_queued_age_s = 0.0;
    std::size_t pool_open = 0, pool_idle = 0, pool_max = 0;
    // The workers' analysis cache (analysis_workers.h).
    std::size_t analysis_cache_bytes = 0;
    std::int64_t preparations_made = 0, preparations_reused = 0, screenings_reused = 0;
    std::int64_t models_a_kept = 0, models_a_reused = 0;
  };
  std::string Render(const Gauges& gauges) const;

 private:
  struct Histogram {
    std::array<std::uint64_t, 16> buckets{};  // per upper bound, not cumulative
    double sum_s = 0.0;
    std::uint64_t count = 0;
  };
  using Labels = std::pair<std::string, std::string>;

  mutable std::mutex mutex_;
  std::map<Labels, Histogram> calls_;     // (method, code)
  std::map<Labels, Histogram> http_;      // (method, status)
  std::map<std::string, Histogram> analyses_;  // outcome
};

// Counts every call the gRPC server answers, the REST gateway's included.
std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface> MetricsInterceptorFactory(Metrics& metrics);

}  // namespace insdiag::server
