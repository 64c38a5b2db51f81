// Stored bench runs: metadata in `runs`, samples packed in
// `run_sample_chunks` (see migrations/0001_runs.sql).
#pragma once

#include <absl/functional/function_ref.h>
#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "insdiag/engine/bench_run.h"
#include "insdiag/kb/connection_pool.h"

namespace insdiag::kb {

// A run as stored, without its samples.
struct StoredRun {
  std::string id;  // UUID, the {run} of runs/{run}
  engine::BenchRunMetadata metadata;
  bool has_temperature = false;
  std::int64_t sample_count = 0;
  double nominal_interval_s = 0.0;
  double duration_s = 0.0;
  double first_t_s = 0.0;
  std::string sha256;      // the upload digest
  std::string request_id;  // empty when the upload had none
  std::int64_t create_time_unix_us = 0;
};

// What identifies an upload: its digest, and for idempotent uploads the
// client's request id and a fingerprint of everything the upload carried.
struct UploadIdentity {
  std::string sha256;
  std::string request_id;           // empty: not idempotent
  std::string request_fingerprint;  // equal fingerprints = the same upload
};

struct RunPage {
  std::vector<StoredRun> runs;
  std::string next_page_token;  // empty on the last page
};

struct RunQuery {
  int page_size = 50;       // clamped to [1, 1000]
  std::string page_token;   // from RunPage::next_page_token
  std::string unit_serial;  // filter when not empty
  // The free metadata (metadata.extra) of each run; false leaves it out: a
  // listing of summaries, bounded in size whatever the runs hold.
  bool with_extra_metadata = true;
};

class RunStore {
 public:
  // `list_pool`: where the listings read (a streaming replica of the
  // database, the server's --read-database-url); null: `pool`.
  explicit RunStore(ConnectionPool& pool, ConnectionPool* list_pool = nullptr)
      : pool_(pool), list_pool_(list_pool != nullptr ? *list_pool : pool) {}

  // Stores the run and its samples in one transaction and registers the unit
  // when its serial is new. With a request id already used: the stored run
  // when the fingerprint matches, else ALREADY_EXISTS naming that run.
  absl::StatusOr<StoredRun> Create(const engine::BenchRun& run, const UploadIdentity& identity);

  // NOT_FOUND when there is no such run; INVALID_ARGUMENT for a malformed id.
  absl::StatusOr<StoredRun> Get(const std::string& run_id);

  // Newest first, keyset-paginated.
  absl::StatusOr<RunPage> List(const RunQuery& query);

  // NOT_FOUND when there is no such run; FAILED_PRECONDITION when a
  // diagnosis or a failure record rests on one of its analyses.
  absl::Status Delete(const std::string& run_id);

  // Calls `consume` with consecutive batches of about `batch_samples` samples
  // in time order until done or `consume` returns false.
  absl::Status ReadSamples(const std::string& run_id, std::size_t batch_samples,
                           absl::FunctionRef<bool(std::span<const engine::ImuSample>)> consume);

 private:
  ConnectionPool& pool_;
  ConnectionPool& list_pool_;
};

}  // namespace insdiag::kb
