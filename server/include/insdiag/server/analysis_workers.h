// The analysis worker pool inside insdiagd: N threads that claim queued
// analyses (kb/analysis_store.h), run the engine on them and store the
// results. Any number of insdiagd processes on one database share the queue.
//
// Per job: what the job does (analysis_job.h: the run read back, the
// engine's request from the job's spec, the engine run) with its progress
// throttled into the row, while a heartbeat renews the lease every lease/3
// and notices cancellation or a lost lease; then the report, its queryable
// parts and the residual series are stored in one transaction. Refusals of
// the input fail the job; other errors put it back in the queue while
// attempts remain (Retryable). Every worker
// also reaps jobs whose lease expired (their worker died).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <condition_variable>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "insdiag/engine/analysis_cache.h"
#include "insdiag/kb/analysis_store.h"
#include "insdiag/kb/connection_pool.h"
#include "insdiag/server/metrics.h"

namespace insdiag::server {

class AnalysisWorkers {
 public:
  struct Options {
    int workers = 1;                                // 0: claim nothing (API only)
    std::chrono::milliseconds lease{30'000};        // a dead worker's job is taken up after this
    std::chrono::milliseconds poll{250};            // idle workers look for jobs this often
    // What the workers keep of the runs they analysed for the next analysis
    // of the same run (engine/analysis_cache.h). With nothing queued, a
    // worker also computes model A of the Add the page offers on the last
    // analysis it finished: an Add from the page then costs model B's pass.
    // 0 keeps nothing.
    // 1 GiB: an eight-hour 50 Hz run's preparation (about 460 MB) under two
    // baselines, or a dozen one-hour 100 Hz runs' (about 97 MB each).
    std::size_t cache_bytes = std::size_t{1024} << 20;
  };

  // `metrics` (may be null) counts each job's outcome and duration.
  AnalysisWorkers(kb::ConnectionPool& pool, Options options, Metrics* metrics = nullptr);
  ~AnalysisWorkers();  // Stop()
  void Start();
  // Stops claiming; waits for running analyses to finish.
  void Stop();
  // A job was queued: idle workers look for it now, not at their next poll.
  void Wake();

  // "host:pid:index" of worker `index`: the lease owner written to the row.
  std::string OwnerName(int index) const;

  // What the workers' cache holds and how often it served.
  engine::AnalysisCache::Counts cache_counts() const { return cache_.counts(); }
  std::size_t cache_bytes() const { return cache_.bytes(); }

 private:
  void Loop(int index);
  // The job's outcome (RunJobOutcome's), counted in the metrics.
  std::string_view RunJob(const kb::ClaimedJob& job, const std::string& owner);
  // RunJob's outcome: "succeeded", "failed", "retried" (queued again), "cancelled" or "lost".
  std::string_view RunJobOutcome(const kb::ClaimedJob& job, const std::string& owner);
  // Sleeps until `duration` passes, a Wake() after the `wakes_seen`-th, or
  // Stop(); false when stopping.
  bool SleepFor(std::chrono::milliseconds duration, std::uint64_t wakes_seen);
  std::uint64_t Wakes();  // Wake() calls so far

  kb::ConnectionPool& pool_;
  Options options_;
  Metrics* metrics_;
  kb::AnalysisStore store_;
  engine::AnalysisCache cache_;
  std::string owner_prefix_;
  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::uint64_t wakes_ = 0;  // Wake() calls so far
  bool started_ = false;
};

}  // namespace insdiag::server
