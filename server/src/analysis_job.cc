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
namespace {

// The stored run and all its samples, as the engine takes them.
absl::StatusOr<engine::BenchRun> ReadRun(kb::ConnectionPool& pool, const std::string& run_id) {
  kb::RunStore runs(pool);
  INSDIAG_ASSIGN_OR_RETURN(auto stored, runs.Get(run_id));
  engine::BenchRun run;
  run.metadata = stored.metadata;
  run.has_temperature = stored.has_temperature;
  run.samples.reserve(static_cast<std::size_t>(stored.sample_count));
  INSDIAG_RETURN_IF_ERROR(runs.ReadSamples(run_id, 1 << 16, [&](std::span<const engine::ImuSample> samples) {
    run.samples.insert(run.samples.end(), samples.begin(), samples.end());
    return true;
  }));
  return run;
}

}  // namespace

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

absl::StatusOr<engine::Analysis> RunAnalysisJob(kb::ConnectionPool& pool, const std::string& run_id,
                                                const v1::AnalysisSpec& spec,
                                                std::function<void(double, std::string_view)> progress) {
  INSDIAG_ASSIGN_OR_RETURN(engine::BenchRun run, ReadRun(pool, run_id));
  std::optional<v1::Analysis> base;
  if (!spec.base_analysis().empty()) {
    INSDIAG_ASSIGN_OR_RETURN(auto base_id, api::ResourceId(spec.base_analysis(), api::kAnalyses, "base_analysis"));
    INSDIAG_ASSIGN_OR_RETURN(auto stored_base, kb::AnalysisStore(pool).Get(base_id, true));
    base = ToProto(stored_base);
  }
  INSDIAG_ASSIGN_OR_RETURN(auto nominal, NominalModelOfUnitType(pool, run.metadata.unit_type));
  INSDIAG_ASSIGN_OR_RETURN(
      engine::AnalysisRequest request,
      EngineRequestOf(spec, std::move(nominal), base.has_value() ? &base->report() : nullptr));
  engine::AnalysisOptions options;
  options.keep_series = true;
  options.progress = std::move(progress);
  try {
    return engine::Analyze(std::move(run), request, options);
  } catch (const std::exception& e) {
    return absl::InternalError(absl::StrCat("the engine failed: ", e.what()));
  }
}

}  // namespace insdiag::server
