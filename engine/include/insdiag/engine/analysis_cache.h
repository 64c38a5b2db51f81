// What analyses of one run share, kept between them so that the page's Add
// costs model B: the run's preparation (its samples screened, the a-priori
// model chosen, the run condensed to its update epochs with the baseline
// effects in its pilot; under another baseline, the screened run is
// condensed again) and, for each earlier
// analysis an Add starts from, model A's scanned outcome. Every stage is
// deterministic in its inputs (ParallelAnalysis.ReportsExactlyWhatOneThreadReports),
// so an analysis that finds them here reports exactly what it would have
// computed (AnalysisCacheTest).
//
// Bounded in bytes: the least recently used preparation leaves first, and a
// preparation larger than the whole bound is not kept. Safe to share between
// threads; an analysis holds what it reads until it ends.
#pragma once

#include <absl/status/statusor.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "insdiag/engine/analysis.h"

namespace insdiag::engine {
namespace pipeline {
struct PreparedRun;
}

// What names an analysis's inputs to the cache, in the caller's stable ids.
struct AnalysisCacheKeys {
  // The run: equal keys name the same samples and metadata (a stored run's
  // id). The request's nominal model and baseline effects are compared by
  // the cache itself.
  std::string run;
  // The earlier analysis AnalysisRequest::identified_base was read from
  // (equal keys, equal bases); empty where there is none.
  std::string identified_base;
};

class AnalysisCache {
 public:
  struct Counts {
    int64_t preparations_reused = 0;
    int64_t preparations_made = 0;
    // Preparations condensed again from a run the cache kept screened
    // under another baseline.
    int64_t screenings_reused = 0;
    int64_t models_a_kept = 0;
    int64_t models_a_reused = 0;
  };

  explicit AnalysisCache(std::size_t capacity_bytes);
  ~AnalysisCache();
  AnalysisCache(const AnalysisCache&) = delete;
  AnalysisCache& operator=(const AnalysisCache&) = delete;

  Counts counts() const;
  std::size_t bytes() const;

  // Analyze, reusing and filling this cache. `read_run` is called only when
  // no preparation of `keys.run` for this request's a-priori inputs is kept.
  // Every analysis through one cache must use the same options apart from
  // `progress` and `keep_series`: the preparation and model A depend on them.
  absl::StatusOr<Analysis> Analyze(const AnalysisCacheKeys& keys,
                                   const std::function<absl::StatusOr<BenchRun>()>& read_run,
                                   const AnalysisRequest& request, const AnalysisOptions& options);

  // Computes and keeps model A of an Add from `request.identified_base`
  // (named by `keys.identified_base`) before anyone asks for the Add: what a
  // server does while it has nothing queued, so that the page's first Add
  // costs model B alone. The Add's request must then carry the same
  // nominal model and baseline effects. Only for a run the cache keeps
  // screened (it never reads the run): false, and nothing kept, otherwise.
  absl::StatusOr<bool> KeepModelA(const AnalysisCacheKeys& keys, const AnalysisRequest& request,
                                  const AnalysisOptions& options);

 private:
  struct Impl;
  // The preparation of the run `run_key` for `request`'s a-priori inputs:
  // kept, condensed from a kept screening, or made from `read_run` (and
  // kept); null where none of these is possible (`read_run` null).
  absl::StatusOr<std::shared_ptr<const pipeline::PreparedRun>> Prepared(
      const std::string& run_key, const std::function<absl::StatusOr<BenchRun>()>* read_run,
      const AnalysisRequest& request, const AnalysisOptions& options);

  std::unique_ptr<Impl> impl_;
};

}  // namespace insdiag::engine
