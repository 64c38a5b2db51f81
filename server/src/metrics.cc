#include "insdiag/server/metrics.h"

#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>
#include <absl/strings/str_replace.h>

#include <chrono>
#include <limits>
#include <span>

namespace insdiag::server {
namespace {

// Upper bounds [s]: requests from a millisecond to minutes (a long upload,
// a watched analysis); analyses from a second to an hour.
constexpr std::array<double, 16> kRequestBoundsS = {0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25,
                                                    0.5,   1.0,    2.5,   5.0,  10.0,  30.0, 60.0, 300.0};
constexpr std::array<double, 16> kAnalysisBoundsS = {0.5,   1.0,   2.0,   5.0,   10.0,   20.0,   30.0,   60.0,
                                                     120.0, 300.0, 600.0, 900.0, 1200.0, 1800.0, 2700.0, 3600.0};

template <typename H>
void Observe(H& h, std::span<const double> bounds, double seconds) {
  for (std::size_t i = 0; i < bounds.size(); ++i) {
    if (seconds <= bounds[i]) {
      ++h.buckets[i];
      break;
    }
  }
  h.sum_s += seconds;
  ++h.count;
}

// A label value with the text format's escapes.
std::string Escaped(const std::string& value) {
  return absl::StrReplaceAll(value, {{"\\", "\\\\"}, {"\"", "\\\""}, {"\n", "\\n"}});
}

std::string Number(double v) { return absl::StrFormat("%.17g", v); }

template <typename H>
void RenderHistogram(std::string& out, const std::string& name, const std::string& labels, const H& h,
                     std::span<const double> bounds) {
  std::uint64_t cumulative = 0;
  const std::string sep = labels.empty() ? "" : ",";
  for (std::size_t i = 0; i < bounds.size(); ++i) {
    cumulative += h.buckets[i];
    absl::StrAppend(&out, name, "_bucket{", labels, sep, "le=\"", Number(bounds[i]), "\"} ", cumulative, "\n");
  }
  absl::StrAppend(&out, name, "_bucket{", labels, sep, "le=\"+Inf\"} ", h.count, "\n");
  absl::StrAppend(&out, name, "_sum{", labels, "} ", Number(h.sum_s), "\n");
  absl::StrAppend(&out, name, "_count{", labels, "} ", h.count, "\n");
}

void Header(std::string& out, const std::string& name, const std::string& type, const std::string& help) {
  absl::StrAppend(&out, "# HELP ", name, " ", help, "\n# TYPE ", name, " ", type, "\n");
}

class MetricsInterceptor : public grpc::experimental::Interceptor {
 public:
  MetricsInterceptor(grpc::experimental::ServerRpcInfo* info, Metrics& metrics)
      : method_(info->method()), metrics_(metrics), start_(std::chrono::steady_clock::now()) {}

  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
    if (methods->QueryInterceptionHookPoint(grpc::experimental::InterceptionHookPoints::PRE_SEND_STATUS)) {
      const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - start_;
      metrics_.CountCall(method_, StatusCodeName(methods->GetSendStatus().error_code()), elapsed.count());
    }
    methods->Proceed();
  }

 private:
  static std::string_view StatusCodeName(grpc::StatusCode code) {
    static constexpr std::array<std::string_view, 17> kNames = {
        "OK",           "CANCELLED",         "UNKNOWN",           "INVALID_ARGUMENT", "DEADLINE_EXCEEDED",
        "NOT_FOUND",    "ALREADY_EXISTS",    "PERMISSION_DENIED", "RESOURCE_EXHAUSTED", "FAILED_PRECONDITION",
        "ABORTED",      "OUT_OF_RANGE",      "UNIMPLEMENTED",     "INTERNAL",          "UNAVAILABLE",
        "DATA_LOSS",    "UNAUTHENTICATED"};
    const auto i = static_cast<std::size_t>(code);
    return i < kNames.size() ? kNames[i] : "UNKNOWN";
  }

  std::string method_;
  Metrics& metrics_;
  std::chrono::steady_clock::time_point start_;
};

class MetricsInterceptorFactoryImpl : public grpc::experimental::ServerInterceptorFactoryInterface {
 public:
  explicit MetricsInterceptorFactoryImpl(Metrics& metrics) : metrics_(metrics) {}
  grpc::experimental::Interceptor* CreateServerInterceptor(grpc::experimental::ServerRpcInfo* info) override {
    return new MetricsInterceptor(info, metrics_);
  }

 private:
  Metrics& metrics_;
};

}  // namespace

void Metrics::CountCall(std::string_view method, std::string_view code, double seconds) {
  std::lock_guard lock(mutex_);
  Observe(calls_[{std::string(method), std::string(code)}], kRequestBoundsS, seconds);
}

void Metrics::CountHttpRequest(std::string_view method, int status, double seconds) {
  std::lock_guard lock(mutex_);
  Observe(http_[{std::string(method), std::to_string(status)}], kRequestBoundsS, seconds);
}

void Metrics::CountAnalysis(std::string_view outcome, double seconds) {
  std::lock_guard lock(mutex_);
  Observe(analyses_[std::string(outcome)], kAnalysisBoundsS, seconds);
}

std::string Metrics::Render(const Gauges& gauges) const {
  std::string out;
  std::lock_guard lock(mutex_);
  const auto calls = [&](const char* name, const char* help, const std::map<Labels, Histogram>& by,
                         const char* first, const char* second) {
    Header(out, absl::StrCat(name, "_total"), "counter", help);
    for (const auto& [labels, h] : by) {
      absl::StrAppend(&out, name, "_total{", first, "=\"", Escaped(labels.first), "\",", second, "=\"",
                      Escaped(labels.second), "\"} ", h.count, "\n");
    }
    Header(out, absl::StrCat(name, "_duration_seconds"), "histogram", absl::StrCat(help, ": duration"));
    for (const auto& [labels, h] : by) {
      RenderHistogram(out, absl::StrCat(name, "_duration_seconds"),
                      absl::StrCat(first, "=\"", Escaped(labels.first), "\",", second, "=\"", Escaped(labels.second),
                                   "\""),
                      h, kRequestBoundsS);
    }
  };
  calls("insdiag_grpc_calls", "gRPC calls answered, the REST gateway's included, by method and status code",
        calls_, "method", "code");
  calls("insdiag_http_requests", "HTTP requests answered, by method and status", http_, "method", "status");

  Header(out, "insdiag_analyses_total", "counter", "analysis jobs ended, by outcome");
  for (const auto& [outcome, h] : analyses_) {
    absl::StrAppend(&out, "insdiag_analyses_total{outcome=\"", Escaped(outcome), "\"} ", h.count, "\n");
  }
  Header(out, "insdiag_analysis_duration_seconds", "histogram", "analysis jobs ended: time from claim to end");
  for (const auto& [outcome, h] : analyses_) {
    RenderHistogram(out, "insdiag_analysis_duration_seconds", absl::StrCat("outcome=\"", Escaped(outcome), "\""), h,
                    kAnalysisBoundsS);
  }

  Header(out, "insdiag_database_up", "gauge", "1 when the database answered the queue's query at this scrape");
  absl::StrAppend(&out, "insdiag_database_up ", gauges.queue_known ? 1 : 0, "\n");
  if (gauges.queue_known) {
    Header(out, "insdiag_jobs_queued", "gauge", "analyses waiting for a worker");
    absl::StrAppend(&out, "insdiag_jobs_queued ", gauges.queued, "\n");
    Header(out, "insdiag_jobs_running", "gauge", "analyses a worker holds");
    absl::StrAppend(&out, "insdiag_jobs_running ", gauges.running, "\n");
    Header(out, "insdiag_jobs_oldest_queued_age_seconds", "gauge", "how long the oldest waiting analysis has waited");
    absl::StrAppend(&out, "insdiag_jobs_oldest_queued_age_seconds ", Number(gauges.oldest_queued_age_s), "\n");
  }
  Header(out, "insdiag_database_connections", "gauge", "the connection pool: open, idle and the most it opens");
  absl::StrAppend(&out, "insdiag_database_connections{state=\"open\"} ", gauges.pool_open, "\n");
  absl::StrAppend(&out, "insdiag_database_connections{state=\"idle\"} ", gauges.pool_idle, "\n");
  absl::StrAppend(&out, "insdiag_database_connections{state=\"max\"} ", gauges.pool_max, "\n");
  Header(out, "insdiag_analysis_cache_bytes", "gauge", "what the workers keep of analysed runs for the next analysis");
  absl::StrAppend(&out, "insdiag_analysis_cache_bytes ", gauges.analysis_cache_bytes, "\n");
  Header(out, "insdiag_analysis_cache_made_total", "counter",
         "runs prepared (screened, condensed) and models A of an Add computed, by part");
  absl::StrAppend(&out, "insdiag_analysis_cache_made_total{part=\"preparation\"} ", gauges.preparations_made, "\n");
  absl::StrAppend(&out, "insdiag_analysis_cache_made_total{part=\"model_a\"} ", gauges.models_a_kept, "\n");
  Header(out, "insdiag_analysis_cache_reused_total", "counter",
         "analyses that took from the cache a run's preparation, its screening (condensed again under another "
         "baseline) or an Add's model A, by part");
  absl::StrAppend(&out, "insdiag_analysis_cache_reused_total{part=\"preparation\"} ", gauges.preparations_reused,
                  "\n");
  absl::StrAppend(&out, "insdiag_analysis_cache_reused_total{part=\"screening\"} ", gauges.screenings_reused,
                  "\n");
  absl::StrAppend(&out, "insdiag_analysis_cache_reused_total{part=\"model_a\"} ", gauges.models_a_reused, "\n");
  return out;
}

std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface> MetricsInterceptorFactory(Metrics& metrics) {
  return std::make_unique<MetricsInterceptorFactoryImpl>(metrics);
}

}  // namespace insdiag::server
