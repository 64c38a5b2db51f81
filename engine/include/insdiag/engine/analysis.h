// The engine's entry point: one bench run and an a-priori error model in, the
// analysis report out (docs/ARCHITECTURE.md, engine pipeline). Analyze runs
// these stages in order, each with explicit inputs and outputs
// (engine/src/analysis.cc, the stages in engine/src/analysis/):
//
//   1. screening: spikes found and repaired in the raw samples, against what
//      the table's motion alone would have made a perfect unit measure
//   2. Allan deviation of the static segments: here when the a-priori model
//      is its fit, else beside stage 4 on another core
//   3. a-priori model: the run's datasheet, else the caller's nominal model
//      (the knowledge base's unit type), else the Allan fit; dominant
//      constant biases removed; baseline effects added
//   4. the run condensed to its update epochs (every later pass filters them)
//   5. identification (analysis/identification.h), unless the request brings
//      model A already identified: Allan noise, terms left at
//      bounds re-tuned, then retargeting [forward filter → smoother →
//      correlation processing of the drifts → re-tuned model] until the
//      parameters settle, the drifts' final values by likelihood; on the
//      first pass the a-priori model's misfit competes with its missing
//      effects
//   6. model A's final pass with the missing-effect scan (analysis/model_pass.h)
//      and its structure tests and ranking (analysis/missing_effects.h):
//      monitoring, fit metrics, ranked candidates, the report
//   7. with `add_effects`: model B = A + effects, its pass, B compared with A;
//      with `discover`: add the most significant effect, re-run, repeat
//      (analysis/model_change.h)
#pragma once

#include <absl/status/statusor.h>

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/filter/forward_filter.h"
#include "insdiag/engine/finder/effect_finder.h"
#include "insdiag/engine/finder/onset_scan.h"
#include "insdiag/engine/ident/allan.h"
#include "insdiag/engine/ident/correlation.h"
#include "insdiag/engine/ident/drift_likelihood.h"
#include "insdiag/engine/ident/retarget.h"
#include "insdiag/engine/ident/static_constants.h"
#include "insdiag/engine/model/effect_catalogue.h"
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
  ReferenceAccuracy reference{.attitude_sigma_rad = 5e-6,
                              .horizontal_position_sigma_m = 1e-6,
                              .vertical_position_sigma_m = 1e-6,
                              .horizontal_velocity_sigma_mps = 1e-7,
                              .vertical_velocity_sigma_mps = 1e-7};
  // Prior σ of an added constant effect with no estimate to start from, in
  // units of the parameter whose effect over one update interval equals the
  // sensor's white noise over that interval (diffuse: the data decide).
  double diffuse_prior_scale = 100.0;
  // Prior σ of an added constant effect that the scan estimated, in multiples
  // of max(|β̂|, 3 σ(β̂)): diffuse against what the data say.
  double estimated_prior_scale = 10.0;
  bool keep_series = false;
  // Identification and retargeting (off: the a-priori model as it is).
  bool identify = true;
  // Constant biases far beyond the a-priori model, measured on the static
  // segments and removed from the samples before any filter pass
  // (ident/static_constants.h).
  bool remove_dominant_constants = true;
  ident::DominantConstantOptions dominant_constants;
  int max_retarget_iterations = 4;
  double settle_log_ratio = 0.1;  // a parameter has settled within 10% (or one σ)
  ident::CorrelationOptions correlation;
  ident::AllanOptions allan;
  // How an Allan-based a-priori model's terms set from bounds are re-tuned
  // by maximum likelihood of the innovations (retarget.h, ScaleUnresolvedNoise).
  ident::NoiseScaleOptions noise_scale;
  // Test a bias random walk on every drift axis by the innovations'
  // likelihood, each fitted with its axis' drift σ (drift_likelihood.h):
  // correlation processing cannot show a walk whose wander is as slow as the
  // run is long.
  bool test_walks_by_likelihood = true;
  // Test a second-order Markov pair on every drift axis the same way: the
  // smoother flattens a poorly observable drift (a horizontal gyro's), and
  // its correlation function then cannot show the oscillation.
  bool test_second_orders_by_likelihood = true;
  // A model that only adds constant or fault effects to one whose walk and
  // pair tests found nothing on an axis takes those outcomes instead of
  // testing again (model B of an Add, each step of the loop, model A from an
  // earlier analysis): an added deterministic effect takes residual from a
  // structure and gives it none. True: every model tests every axis again.
  bool retest_settled_structures = false;
  // How the drifts' σ (and τ where the run resolves it) are identified by
  // maximum likelihood of the innovations (drift_likelihood.h), started from
  // correlation processing's estimates. Every drift the likelihood fits is
  // bounded by what the static segments' raw samples allow
  // (ident/drift_ceiling.h), at the monitor's family-wise α: a drift the
  // run's motion leaves unobservable otherwise wanders to values that absorb
  // a fault (the run's context holds them: analysis/run_context.h).
  ident::DriftLikelihoodOptions drift_likelihood;
  // Where the a-priori model's misfit competes with its missing effects, its
  // drifts are searched from these starts besides the a-priori values
  // (ident::IdentifyDriftsFromStarts).
  ident::DriftStartOptions drift_starts;
  FinderOptions finder;
  // Bias steps and ramps at an unknown onset (finder/onset_scan.h).
  OnsetScanOptions onset_scan;
  // Time segments of the "where it shows" breakdown.
  double segment_s = 60.0;
  int max_discovery_steps = 8;
  // Progress of a long analysis: fraction done in [0, 1] and the stage's name.
  std::function<void(double, std::string_view)> progress;

  absl::Status Validate() const;
};

// A model an earlier analysis of the same run identified, with what that
// analysis reported of the identification (its report's model and
// `identified`) and of its likelihood tests of random structures (its
// report's candidates from them: what it found nothing in is not tested
// again).
struct IdentifiedModel {
  ErrorModel model;
  std::vector<ParameterEstimate> identified;
  std::vector<EffectCandidate> structure_outcomes;
};

struct AnalysisRequest {
  // The unit type's nominal model from the knowledge base, if any.
  std::optional<ErrorModel> nominal;
  // Model A: catalogue effects on top of the base model (terms or families).
  std::vector<std::string> baseline_effects;
  // Model B = A + these; the report is B's, compared with A.
  std::vector<std::string> add_effects;
  // Walk the loop from model A (ignores add_effects).
  bool discover = false;
  // Model A as an earlier analysis of this run identified it (with the
  // baseline effects in it): stage 5 is skipped and model A's pass starts
  // from it, so that adding an effect costs model A's and model B's passes
  // only. Unset: model A is identified here.
  std::optional<IdentifiedModel> identified_base;
};

struct Analysis {
  AnalysisReport report;
  AnalysisSeries series;  // filled when AnalysisOptions::keep_series
  ErrorModel model;       // the model the report was computed with
  // Model A's own report (its candidates, identification, fit) when effects
  // were added or discovered: what the same run analysed without them
  // reports, so that a caller comparing the two need not analyse twice.
  std::optional<AnalysisReport> base_report;
};

absl::StatusOr<Analysis> Analyze(const BenchRun& run, const AnalysisRequest& request,
                                 const AnalysisOptions& options);
// The same, working on `run` in place where the caller no longer needs it:
// the analysis then holds one copy of the samples, not two.
absl::StatusOr<Analysis> Analyze(BenchRun&& run, const AnalysisRequest& request,
                                 const AnalysisOptions& options);

// The a-priori model from the datasheet, completed from `nominal`; an error
// naming the missing values when neither has them.
absl::StatusOr<ErrorModel> APrioriModel(const BenchRun& run, const std::optional<ErrorModel>& nominal,
                                        const ReferenceAccuracy& reference);

// Adds catalogue terms to `model` with diffuse priors scaled to the run.
absl::Status AddEffects(const BenchRun& run, const std::vector<std::string>& selectors, double update_interval_s,
                        double diffuse_prior_scale, ErrorModel& model);
// The same for terms already parsed.
absl::Status AddEffects(const BenchRun& run, const std::vector<SelectedTerm>& selected,
                        double update_interval_s, double diffuse_prior_scale, ErrorModel& model);

}  // namespace insdiag::engine
