// Analyses as jobs (migrations/0002_knowledge.sql, table `analyses`).
//
// Life of a job:
//   Create            QUEUED
//   Claim             RUNNING, lease_owner = worker, lease_expires = now + lease,
//                     attempts + 1 (SELECT … FOR UPDATE SKIP LOCKED LIMIT 1:
//                     concurrent claimers never get the same row)
//   Heartbeat         extends the lease while the worker runs; tells it when
//                     the job was cancelled or taken from it
//   Complete / Fail   SUCCEEDED with the report and its queryable parts /
//                     FAILED with the error (or QUEUED again when retryable)
//   Reap              RUNNING jobs whose lease expired (their worker died):
//                     QUEUED again, or FAILED after max_attempts
//   Cancel            QUEUED → CANCELLED at once; RUNNING → cancel_requested,
//                     and the worker ends it CANCELLED
// Every transition checks the lease owner, so a worker that lost its lease
// (it stalled past the expiry and another took the job) cannot overwrite.
#pragma once

#include <absl/functional/function_ref.h>
#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <chrono>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "insdiag/engine/report.h"
#include "insdiag/kb/analysis.h"
#include "insdiag/kb/connection_pool.h"

namespace insdiag::kb {

struct AnalysisQuery {
  int page_size = 50;
  std::string page_token;
  std::string run_id;       // filter when set
  std::string unit_serial;  // filter when set
  bool include_reports = false;
};

struct AnalysisPage {
  std::vector<Analysis> analyses;
  std::string next_page_token;
};

// A job handed to a worker.
struct ClaimedJob {
  std::string analysis_id;
  std::string run_id;
  std::string encoded_spec;  // as Create stored it
  int attempt = 0;
};

struct LeaseState {
  bool owned = false;             // false: the lease was lost (expired and reaped)
  bool cancel_requested = false;
};

struct ReapReport {
  int requeued = 0;
  int failed = 0;
};

// The job queue at one moment, for operations.
struct QueueStats {
  std::int64_t queued = 0;
  std::int64_t running = 0;
  double oldest_queued_age_s = 0.0;  // 0 when nothing waits
};

class AnalysisStore {
 public:
  // `list_pool`: where the listings read (a streaming replica of the
  // database, the server's --read-database-url); null: `pool`.
  explicit AnalysisStore(ConnectionPool& pool, ConnectionPool* list_pool = nullptr)
      : pool_(pool), list_pool_(list_pool != nullptr ? *list_pool : pool) {}

  // Queues an analysis of runs/{run_id} with its spec as the edge encoded
  // it (same spec, same bytes). With a request id already used for the same
  // run and spec: that analysis; for another: ALREADY_EXISTS. NOT_FOUND for
  // an unknown run.
  absl::StatusOr<Analysis> Create(const std::string& run_id, const std::string& encoded_spec,
                                  const std::string& request_id, int max_attempts = 3);

  // NOT_FOUND / INVALID_ARGUMENT (malformed id).
  absl::StatusOr<Analysis> Get(const std::string& analysis_id, bool include_report = true);
  absl::StatusOr<AnalysisPage> List(const AnalysisQuery& query);

  // The oldest queued job, now RUNNING under `owner`'s lease; nullopt when none waits.
  absl::StatusOr<std::optional<ClaimedJob>> Claim(const std::string& owner, std::chrono::milliseconds lease);
  absl::StatusOr<LeaseState> Heartbeat(const std::string& analysis_id, const std::string& owner,
                                       std::chrono::milliseconds lease);
  // Progress of a running job (and a lease renewal).
  absl::StatusOr<LeaseState> UpdateProgress(const std::string& analysis_id, const std::string& owner,
                                            double fraction, const std::string& stage,
                                            std::chrono::milliseconds lease);
  // Stores the report (its bytes as the edge encoded them), its queryable
  // rows and the series in one transaction. FAILED_PRECONDITION when `owner`
  // no longer holds the job.
  absl::Status Complete(const std::string& analysis_id, const std::string& owner, const std::string& encoded_report,
                        const ReportRows& rows, const engine::AnalysisSeries* series);
  // FAILED with `error`, or QUEUED again when `retry` and attempts remain.
  absl::Status Fail(const std::string& analysis_id, const std::string& owner, const absl::Status& error, bool retry);
  // Ends a job whose cancellation was requested.
  absl::Status MarkCancelled(const std::string& analysis_id, const std::string& owner);
  absl::StatusOr<ReapReport> Reap();

  absl::StatusOr<Analysis> Cancel(const std::string& analysis_id);

  // How many jobs wait and run, and how long the oldest has waited.
  absl::StatusOr<QueueStats> Queue();

  // The stored series, `chunk_points` points at a time, channel by channel
  // (only `channels` when not empty). FAILED_PRECONDITION before SUCCEEDED.
  absl::Status ReadSeries(const std::string& analysis_id, const std::vector<std::string>& channels,
                          std::size_t chunk_points, absl::FunctionRef<bool(std::span<const ResidualPoint>)> consume);

 private:
  ConnectionPool& pool_;
  ConnectionPool& list_pool_;
};

}  // namespace insdiag::kb
