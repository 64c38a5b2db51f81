// The engine's entry point: one bench run and an a-priori error model in, the
// analysis report out (docs/ARCHITECTURE.md, engine pipeline):
//
//   screen raw samples for spikes → strapdown mechanisation → forward
//   error-state filter → smoother → monitoring → fit metrics
//   (→ identification and the missing-effect scan, where enabled)
//
// The a-priori model comes, per parameter, from the run's datasheet metadata,
// else from the caller's nominal model (the knowledge base's unit type), else
// from identification on the data itself.
#pragma once

#include <absl/status/statusor.h>

#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/filter/forward_filter.h"
#include "insdiag/engine/model/error_model.h"
#include "insdiag/engine/monitor/monitoring.h"
#include "insdiag/engine/monitor/sample_screening.h"
#include "insdiag/engine/report.h"

namespace insdiag::engine {

struct AnalysisOptions {
  FilterOptions filter;
  MonitorOptions monitor;
  ScreeningOptions screening;
  // Accuracy of the bench's reference (table encoders, surveyed site, a body
  // at rest): a precision rate table reads attitude to about an arc-second.
  ReferenceAccuracy reference{.attitude_sigma_rad = 5e-6, .position_sigma_m = 1e-6, .velocity_sigma_mps = 1e-7};
  // Prior σ of an added constant effect with no estimate to start from, in
  // units of the parameter whose effect over one update interval equals the
  // sensor's white noise over that interval (diffuse: the data decide).
  double diffuse_prior_scale = 100.0;
  bool keep_series = false;
  // Progress of a long analysis: fraction done in [0, 1] and the stage's name.
  std::function<void(double, std::string_view)> progress;

  absl::Status Validate() const;
};

struct AnalysisRequest {
  // The unit type's nominal model from the knowledge base, if any.
  std::optional<ErrorModel> nominal;
  // Catalogue effects to put into the model: terms ("gyro_scale_factor.z") or families.
  std::vector<std::string> add_effects;
};

struct Analysis {
  AnalysisReport report;
  AnalysisSeries series;  // filled when AnalysisOptions::keep_series
  ErrorModel model;       // the model the report was computed with
};

absl::StatusOr<Analysis> Analyze(const BenchRun& run, const AnalysisRequest& request,
                                 const AnalysisOptions& options);

// The a-priori model from the datasheet, completed from `nominal`; an error
// naming the missing values when neither has them.
absl::StatusOr<ErrorModel> APrioriModel(const BenchRun& run, const std::optional<ErrorModel>& nominal,
                                        const ReferenceAccuracy& reference);

// Adds catalogue terms to `model` with diffuse priors scaled to the run.
absl::Status AddEffects(const BenchRun& run, const std::vector<std::string>& selectors, double update_interval_s,
                        double diffuse_prior_scale, ErrorModel& model);

}  // namespace insdiag::engine
