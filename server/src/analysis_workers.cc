#include "insdiag/server/analysis_workers.h"

#include <absl/strings/str_cat.h>
#include <unistd.h>

#include "analysis_codec.h"
#include "insdiag/api/report_codec.h"
#include "insdiag/engine/status_macros.h"
#include "insdiag/server/analysis_job.h"
#include "insdiag/server/server_log.h"

namespace insdiag::server {
namespace {

constexpr std::chrono::milliseconds kProgressInterval{300};

// Renews a job's lease every lease/3 on a thread of its own until Finish(),
// and keeps what the store says of the lease: lost (expired and reaped) or
// asked to cancel. Progress updates report the same and are noted too.
class LeaseHeartbeat {
 public:
  LeaseHeartbeat(kb::AnalysisStore& store, const std::string& analysis_id, const std::string& owner,
                 std::chrono::milliseconds lease)
      : store_(store), analysis_id_(analysis_id), owner_(owner), lease_(lease), thread_([this] { Run(); }) {}
  ~LeaseHeartbeat() { Finish(); }
  LeaseHeartbeat(const LeaseHeartbeat&) = delete;
  LeaseHeartbeat& operator=(const LeaseHeartbeat&) = delete;

  void Note(const kb::LeaseState& state) {
    if (!state.owned) lost_ = true;
    if (state.cancel_requested) cancelled_ = true;
  }
  bool lost() const { return lost_; }
  bool cancelled() const { return cancelled_; }

  void Finish() {
    {
      std::lock_guard lock(mutex_);
      done_ = true;
    }
    wake_.notify_all();
    if (thread_.joinable()) thread_.join();
  }

 private:
  void Run() {
    std::unique_lock lock(mutex_);
    while (!wake_.wait_for(lock, lease_ / 3, [this] { return done_; })) {
      // The database away: try again at the next beat; the lease may still hold.
      if (auto state = store_.Heartbeat(analysis_id_, owner_, lease_); state.ok()) Note(*state);
    }
  }

  kb::AnalysisStore& store_;
  const std::string& analysis_id_;
  const std::string& owner_;
  const std::chrono::milliseconds lease_;
  std::atomic<bool> lost_{false};
  std::atomic<bool> cancelled_{false};
  std::mutex mutex_;
  std::condition_variable wake_;
  bool done_ = false;
  std::thread thread_;  // last: it starts once everything above is built
};

std::string HostName() {
  char name[256] = {};
  if (gethostname(name, sizeof name - 1) != 0) return "host";
  return name;
}

}  // namespace

AnalysisWorkers::AnalysisWorkers(kb::ConnectionPool& pool, Options options, Metrics* metrics)
    : pool_(pool), options_(options), metrics_(metrics), store_(pool), cache_(options.cache_bytes),
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

bool AnalysisWorkers::SleepFor(std::chrono::milliseconds duration, std::uint64_t wakes_seen) {
  std::unique_lock lock(mutex_);
  wake_.wait_for(lock, duration, [&] { return stopping_ || wakes_ != wakes_seen; });
  return !stopping_;
}

std::uint64_t AnalysisWorkers::Wakes() {
  std::lock_guard lock(mutex_);
  return wakes_;
}

void AnalysisWorkers::Wake() {
  {
    std::lock_guard lock(mutex_);
    ++wakes_;
  }
  wake_.notify_all();
}

void AnalysisWorkers::Loop(int index) {
  const std::string owner = OwnerName(index);
  auto last_reap = std::chrono::steady_clock::now() - options_.lease;
  std::optional<kb::ClaimedJob> idle_work;  // the last job that succeeded, until the queue is empty
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
    // Before the claim: a job queued while it runs is not slept past.
    const std::uint64_t wakes_seen = Wakes();
    auto job = store_.Claim(owner, options_.lease);
    if (!job.ok()) {
      Log(LogLevel::kError, absl::StrCat(owner, ": cannot claim jobs: ", job.status().message()));
      if (!SleepFor(options_.poll * 4, wakes_seen)) return;
      continue;
    }
    if (!job->has_value()) {
      // Nothing queued: model A of the Add the page offers on the last
      // analysis this worker finished, so that the first Add costs model B.
      if (idle_work.has_value()) {
        const auto kept = KeepModelAForAdds(pool_, idle_work->run_id, idle_work->analysis_id, cache_);
        if (!kept.ok()) {
          Log(LogLevel::kWarning, absl::StrCat(owner, ": model A of analyses/", idle_work->analysis_id,
                                               " not kept for its Adds: ", kept.status().message()));
        }
        idle_work.reset();
        continue;
      }
      if (!SleepFor(options_.poll, wakes_seen)) return;
      continue;
    }
    if (RunJob(**job, owner) == "succeeded" && options_.cache_bytes > 0) idle_work = **job;
  }
}

std::string_view AnalysisWorkers::RunJob(const kb::ClaimedJob& job, const std::string& owner) {
  const auto start = std::chrono::steady_clock::now();
  const std::string_view outcome = RunJobOutcome(job, owner);
  const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - start;
  if (metrics_ != nullptr) metrics_->CountAnalysis(outcome, elapsed.count());
  return outcome;
}

std::string_view AnalysisWorkers::RunJobOutcome(const kb::ClaimedJob& job, const std::string& owner) {
  LeaseHeartbeat heartbeat(store_, job.analysis_id, owner, options_.lease);
  auto last_progress = std::chrono::steady_clock::now() - kProgressInterval;
  auto progress = [&](double fraction, std::string_view stage) {
    const auto now = std::chrono::steady_clock::now();
    if (now - last_progress < kProgressInterval && fraction < 1.0) return;
    last_progress = now;
    auto state = store_.UpdateProgress(job.analysis_id, owner, fraction, std::string(stage), options_.lease);
    if (state.ok()) heartbeat.Note(*state);
  };
  const absl::Status status = [&]() -> absl::Status {
    INSDIAG_ASSIGN_OR_RETURN(engine::Analysis analysis,
                             RunAnalysisJob(pool_, job.run_id, SpecOf(job.encoded_spec), progress,
                                            options_.cache_bytes > 0 ? &cache_ : nullptr));
    if (heartbeat.lost() || heartbeat.cancelled()) return absl::OkStatus();
    const v1::AnalysisReport report = api::ToProto(analysis.report, analysis.model);
    return store_.Complete(job.analysis_id, owner, EncodedReport(report), ReportRowsOf(report), &analysis.series);
  }();
  heartbeat.Finish();
  if (heartbeat.lost()) {
    Log(LogLevel::kWarning, absl::StrCat(owner, ": lost the lease of analyses/", job.analysis_id, "; result dropped"));
    return "lost";
  }
  if (heartbeat.cancelled()) {
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
