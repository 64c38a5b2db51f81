// What one queued analysis does, apart from the worker pool that claims it
// (analysis_workers.h) and keeps its lease: the job's spec mapped to the
// engine's request, the stored run read back, the engine run, and which
// failures are worth another attempt.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <string_view>

#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include "insdiag/engine/analysis.h"
#include "insdiag/engine/analysis_cache.h"
#include "insdiag/kb/connection_pool.h"
#include "insdiag/v1/analyses.pb.h"

namespace insdiag::server {

// The engine's request for `spec`: the effects to add (model B) or the loop
// to walk, model A's baseline effects, and the a-priori model: the unit
// type's nominal model (`nominal`, none when the knowledge base has none)
// with the spec's parameter overrides on it. `base_report`: the earlier
// analysis `spec.base_analysis` names, whose identified model is model A
// (null when it names none). INVALID_ARGUMENT names the spec's field.
absl::StatusOr<engine::AnalysisRequest> EngineRequestOf(const v1::AnalysisSpec& spec,
                                                         std::optional<engine::ErrorModel> nominal,
                                                         const v1::AnalysisReport* base_report);

// An error that another attempt may not meet: anything but the engine's and
// the store's refusals of their input, which are properties of the input.
bool Retryable(const absl::Status& status);

// The job's analysis: the run `run_id` read from the store, the base
// analysis and the unit type's nominal model looked up, the engine run on
// them. `progress` receives the engine's stages. `cache` (may be null) keeps
// what the next analysis of the run reuses: its preparation, and model A of
// an Add from a base analysis (engine/analysis_cache.h).
absl::StatusOr<engine::Analysis> RunAnalysisJob(kb::ConnectionPool& pool, const std::string& run_id,
                                                const v1::AnalysisSpec& spec,
                                                std::function<void(double, std::string_view)> progress,
                                                engine::AnalysisCache* cache = nullptr);

// Keeps in `cache` model A of the Add the page offers on the succeeded
// analysis `analysis_id` of run `run_id` (the request that Add sends, with
// the analysis as its base): the Add then costs model B's pass alone. Only
// for a run the cache keeps screened: false, and nothing kept, otherwise.
absl::StatusOr<bool> KeepModelAForAdds(kb::ConnectionPool& pool, const std::string& run_id,
                                       const std::string& analysis_id, engine::AnalysisCache& cache);

// An analysis from `base` whose spec names no baseline starts from the
// effects of the base's model.
void DefaultBaselineToBase(const v1::Analysis& base, v1::AnalysisSpec& spec);

}  // namespace insdiag::server
