#include "insdiag/server/analysis_workers.h"

#include <absl/strings/str_cat.h>
#include <unistd.h>

#include <exception>

#include "insdiag/api/report_codec.h"
#include "insdiag/api/resource_names.h"
#include "insdiag/engine/analysis.h"
#include "insdiag/engine/model/parameters.h"
#include "insdiag/engine/status_macros.h"
#include "insdiag/kb/run_store.h"
#include "insdiag/server/server_log.h"
#include "insdiag/server/unit_type_models.h"

namespace insdiag::server {
namespace {

constexpr std::chrono::milliseconds kProgressInterval{300};

// Engine refusals are properties of the input: retrying cannot help.
bool Retryable(const absl::Status& status) {
  return status.code() != absl::StatusCode::kInvalidArgument &&
         status.code() != absl::StatusCode::kFailedPrecondition && status.code() != absl::StatusCode::kNotFound &&
         status.code() != absl::StatusCode::kOutOfRange;
}

std::string HostName() {
  char name[256] = {};
  if (gethostname(name, sizeof name - 1) != 0) return "host";
  return name;
}

}  // namespace

AnalysisWorkers::AnalysisWorkers(kb::ConnectionPool& pool, Options options, Metrics* metrics)
    : pool_(pool), options_(options), metrics_(metrics), store_(pool),
      owner_prefix_(absl::StrCat(HostName(), ":", getpid())) {}

AnalysisWorkers::~AnalysisWorkers() { Stop(); }

std::string AnalysisWorkers::OwnerName(int index) const { return absl::StrCat(owner_prefix_, ":", index); }

void AnalysisWorkers::Start() {
  std::lock_guard lock(mutex_);
  if (started_) return;
  started_ = true;
  for (int i = 0; i < options_.workers; ++i) threads_.emplace_back([this, i] { Loop(i); });
}

void AnalysisWorkers::Stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  for (auto& t : threads_) {
    if (t.joinable()) t.join();
  }
  threads_.clear();
}

bool AnalysisWorkers::SleepFor(std::chrono::milliseconds duration) {
  std::unique_lock lock(mutex_);
  wake_.wait_for(lock, duration, [this] { return stopping_; });
  return !stopping_;
}

void AnalysisWorkers::Loop(int index) {
  const std::string owner = OwnerName(index);
  auto last_reap = std::chrono::steady_clock::now() - options_.lease;
  for (;;) {
    {
      std::lock_guard lock(mutex_);
      if (stopping_) return;
    }
    // Jobs of dead workers: any live worker puts them back (SKIP LOCKED keeps reapers apart).
    if (std::chrono::steady_clock::now() - last_reap > options_.lease / 4) {
      last_reap = std::chrono::steady_clock::now();
      if (auto reaped = store_.Reap(); reaped.ok() && (reaped->requeued + reaped->failed) > 0) {
        Log(LogLevel::kWarning, absl::StrCat(owner, ": lease expired on ", reaped->requeued, " job(s) requeued, ",
                                             reaped->failed, " failed after their last attempt"));
      }
    }
    auto job = store_.Claim(owner, options_.lease);
    if (!job.ok()) {
      Log(LogLevel::kError, absl::StrCat(owner, ": cannot claim jobs: ", job.status().message()));
      if (!SleepFor(options_.poll * 4)) return;
      continue;
    }
    if (!job->has_value()) {
      if (!SleepFor(options_.poll)) return;
      continue;
    }
    RunJob(**job, owner);
  }
}

void AnalysisWorkers::RunJob(const kb::ClaimedJob& job, const std::string& owner) {
  const auto start = std::chrono::steady_clock::now();
  const std::string_view outcome = RunJobOutcome(job, owner);
  const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - start;
  if (metrics_ != nullptr) metrics_->CountAnalysis(outcome, elapsed.count());
}

std::string_view AnalysisWorkers::RunJobOutcome(const kb::ClaimedJob& job, const std::string& owner) {
  std::atomic<bool> cancelled{false};
  std::atomic<bool> lost{false};
  std::atomic<bool> done{false};
  std::mutex heartbeat_mutex;
  std::condition_variable heartbeat_wake;
  std::thread heartbeat([&] {
    std::unique_lock lock(heartbeat_mutex);
    while (!heartbeat_wake.wait_for(lock, options_.lease / 3, [&] { return done.load(); })) {
      auto state = store_.Heartbeat(job.analysis_id, owner, options_.lease);
      if (!state.ok()) continue;  // the database is away: try again; the lease may still hold
      if (!state->owned) lost = true;
      if (state->cancel_requested) cancelled = true;
    }
  });
  const auto finish_heartbeat = [&] {
    {
      std::lock_guard lock(heartbeat_mutex);
      done = true;
    }
    heartbeat_wake.notify_all();
    heartbeat.join();
  };

  absl::Status status = [&]() -> absl::Status {
    kb::RunStore runs(pool_);
    INSDIAG_ASSIGN_OR_RETURN(auto stored, runs.Get(job.run_id));
    engine::BenchRun run;
    run.metadata = stored.metadata;
    run.has_temperature = stored.has_temperature;
    run.samples.reserve(static_cast<std::size_t>(stored.sample_count));
    if (auto read = runs.ReadSamples(job.run_id, 1 << 16,
                                     [&](std::span<const engine::ImuSample> samples) {
                                       run.samples.insert(run.samples.end(), samples.begin(), samples.end());
                                       return true;
                                     });
        !read.ok()) {
      return read;
    }
    engine::AnalysisRequest request;
    const v1::ErrorModel& asked = job.spec.model();
    request.add_effects.assign(asked.effects().begin(), asked.effects().end());
    request.baseline_effects.assign(job.spec.baseline().effects().begin(), job.spec.baseline().effects().end());
    request.discover = job.spec.discover();
    if (!job.spec.base_analysis().empty()) {
      INSDIAG_ASSIGN_OR_RETURN(
          auto base_id, api::ResourceId(job.spec.base_analysis(), api::kAnalyses, "base_analysis"));
      INSDIAG_ASSIGN_OR_RETURN(auto base, store_.Get(base_id, true));
      INSDIAG_ASSIGN_OR_RETURN(auto identified, api::IdentifiedModelOf(base.report()));
      request.identified_base = std::move(identified);
    }
    auto nominal = NominalModelOfUnitType(pool_, run.metadata.unit_type);
    if (!nominal.ok()) return nominal.status();
    request.nominal = *std::move(nominal);
    if (asked.parameters_size() > 0) {
      if (!request.nominal) request.nominal = engine::ErrorModel{};
      for (const auto& p : asked.parameters()) {
        if (auto set = engine::SetParameter(p.name(), p.value(), *request.nominal); !set.ok()) {
          return absl::InvalidArgumentError(absl::StrCat("analysis.model.parameters: ", set.message()));
        }
      }
    }
    engine::AnalysisOptions options;
    options.keep_series = true;
    auto last_progress = std::chrono::steady_clock::now() - kProgressInterval;
    options.progress = [&](double fraction, std::string_view stage) {
      const auto now = std::chrono::steady_clock::now();
      if (now - last_progress < kProgressInterval && fraction < 1.0) return;
      last_progress = now;
      auto state = store_.UpdateProgress(job.analysis_id, owner, fraction, std::string(stage), options_.lease);
      if (state.ok()) {
        if (!state->owned) lost = true;
        if (state->cancel_requested) cancelled = true;
      }
    };
    absl::StatusOr<engine::Analysis> analysis = absl::InternalError("the engine did not run");
    try {
      analysis = engine::Analyze(std::move(run), request, options);
    } catch (const std::exception& e) {
      return absl::InternalError(absl::StrCat("the engine failed: ", e.what()));
    }
    if (!analysis.ok()) return analysis.status();
    if (lost || cancelled) return absl::OkStatus();
    return store_.Complete(job.analysis_id, owner, api::ToProto(analysis->report, analysis->model), &analysis->series);
  }();
  finish_heartbeat();
  if (lost) {
    Log(LogLevel::kWarning, absl::StrCat(owner, ": lost the lease of analyses/", job.analysis_id, "; result dropped"));
    return "lost";
  }
  if (cancelled) {
    (void)store_.MarkCancelled(job.analysis_id, owner);
    return "cancelled";
  }
  if (!status.ok()) {
    const bool retry = Retryable(status);
    Log(retry ? LogLevel::kWarning : LogLevel::kError,
        absl::StrCat(owner, ": analyses/", job.analysis_id, " attempt ", job.attempt,
                     retry ? " failed (will retry): " : " failed: ", status.message()));
    (void)store_.Fail(job.analysis_id, owner, status, retry);
    return retry ? "retried" : "failed";
  }
  return "succeeded";
}

}  // namespace insdiag::server
