#include "insdiag/server/analysis_job.h"

#include <absl/strings/str_cat.h>

#include <exception>
#include <span>
#include <utility>

#include "analysis_codec.h"
#include "insdiag/api/report_codec.h"
#include "insdiag/api/resource_names.h"
#include "insdiag/engine/model/parameters.h"
#include "insdiag/engine/status_macros.h"
#include "insdiag/kb/analysis_store.h"
#include "insdiag/kb/run_store.h"
#include "insdiag/server/unit_type_models.h"

namespace insdiag::server {

absl::StatusOr<engine::AnalysisRequest> EngineRequestOf(const v1::AnalysisSpec& spec,
                                                         std::optional<engine::ErrorModel> nominal,
                                                         const v1::AnalysisReport* base_report) {
  engine::AnalysisRequest request;
  request.add_effects.assign(spec.model().effects().begin(), spec.model().effects().end());
  request.baseline_effects.assign(spec.baseline().effects().begin(), spec.baseline().effects().end());
  request.discover = spec.discover();
  if (base_report != nullptr) {
    INSDIAG_ASSIGN_OR_RETURN(auto identified, api::IdentifiedModelOf(*base_report));
    request.identified_base = std::move(identified);
  }
  request.nominal = std::move(nominal);
  if (spec.model().parameters_size() > 0) {
    if (!request.nominal) request.nominal = engine::ErrorModel{};
    for (const auto& p : spec.model().parameters()) {
      if (auto set = engine::SetParameter(p.name(), p.value(), *request.nominal); !set.ok()) {
        return absl::InvalidArgumentError(absl::StrCat("analysis.model.parameters: ", set.message()));
      }
    }
  }
  return request;
}

bool Retryable(const absl::Status& status) {
  return status.code() != absl::StatusCode::kInvalidArgument &&
         status.code() != absl::StatusCode::kFailedPrecondition && status.code() != absl::StatusCode::kNotFound &&
         status.code() != absl::StatusCode::kOutOfRange;
}

void DefaultBaselineToBase(const v1::Analysis& base, v1::AnalysisSpec& spec) {
  if (spec.baseline().effects_size() == 0) {
    *spec.mutable_baseline()->mutable_effects() = base.report().model().effects();
  }
}

namespace {

// The stored run `stored` describes and all its samples, as the engine takes them.
absl::StatusOr<engine::BenchRun> ReadRun(kb::ConnectionPool& pool, const kb::StoredRun& stored) {
  engine::BenchRun run;
  run.metadata = stored.metadata;
  run.has_temperature = stored.has_temperature;
  run.samples.reserve(static_cast<std::size_t>(stored.sample_count));
  INSDIAG_RETURN_IF_ERROR(
      kb::RunStore(pool).ReadSamples(stored.id, 1 << 16, [&](std::span<const engine::ImuSample> samples) {
        run.samples.insert(run.samples.end(), samples.begin(), samples.end());
        return true;
      }));
  return run;
}

// What a job of `spec` on run `run_id` analyses: the stored run, the
// engine's request and options, and the names the analysis cache keeps its
// parts under.
struct JobInputs {
  kb::StoredRun stored;
  engine::AnalysisRequest request;
  engine::AnalysisOptions options;
  engine::AnalysisCacheKeys keys;
};

absl::StatusOr<JobInputs> InputsOf(kb::ConnectionPool& pool, const std::string& run_id,
                                   v1::AnalysisSpec spec) {
  JobInputs in;
  INSDIAG_ASSIGN_OR_RETURN(in.stored, kb::RunStore(pool).Get(run_id));
  std::optional<v1::Analysis> base;
  if (!spec.base_analysis().empty()) {
    INSDIAG_ASSIGN_OR_RETURN(auto base_id, api::ResourceId(spec.base_analysis(), api::kAnalyses, "base_analysis"));
    INSDIAG_ASSIGN_OR_RETURN(auto stored_base, kb::AnalysisStore(pool).Get(base_id, true));
    base = ToProto(stored_base);
    DefaultBaselineToBase(*base, spec);
    in.keys.identified_base = base_id;
  }
  INSDIAG_ASSIGN_OR_RETURN(auto nominal, NominalModelOfUnitType(pool, in.stored.metadata.unit_type));
  INSDIAG_ASSIGN_OR_RETURN(in.request, EngineRequestOf(spec, std::move(nominal),
                                                       base.has_value() ? &base->report() : nullptr));
  in.options.keep_series = true;
  // A run's samples never change once stored; its digest and count name them.
  in.keys.run = absl::StrCat(run_id, "/", in.stored.sample_count, "/", in.stored.sha256);
  return in;
}

}  // namespace

absl::StatusOr<engine::Analysis> RunAnalysisJob(kb::ConnectionPool& pool, const std::string& run_id,
                                                const v1::AnalysisSpec& spec,
                                                std::function<void(double, std::string_view)> progress,
                                                engine::AnalysisCache* cache) {
  INSDIAG_ASSIGN_OR_RETURN(JobInputs in, InputsOf(pool, run_id, spec));
  in.options.progress = std::move(progress);
  try {
    if (cache == nullptr) {
      INSDIAG_ASSIGN_OR_RETURN(engine::BenchRun run, ReadRun(pool, in.stored));
      return engine::Analyze(std::move(run), in.request, in.options);
    }
    return cache->Analyze(in.keys, [&] { return ReadRun(pool, in.stored); }, in.request, in.options);
  } catch (const std::exception& e) {
    return absl::InternalError(absl::StrCat("the engine failed: ", e.what()));
  }
}

absl::StatusOr<bool> KeepModelAForAdds(kb::ConnectionPool& pool, const std::string& run_id,
                                       const std::string& analysis_id, engine::AnalysisCache& cache) {
  // The page's Add: this analysis as its base (the baseline its model's effects).
  v1::AnalysisSpec spec;
  spec.set_base_analysis(api::ResourceName(api::kAnalyses, analysis_id));
  INSDIAG_ASSIGN_OR_RETURN(JobInputs in, InputsOf(pool, run_id, spec));
  try {
    return cache.KeepModelA(in.keys, in.request, in.options);
  } catch (const std::exception& e) {
    return absl::InternalError(absl::StrCat("the engine failed: ", e.what()));
  }
}

}  // namespace insdiag::server
