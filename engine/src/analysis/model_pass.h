// One model's pass over the run — the filter, the smoother, the monitor and,
// when asked, the missing-effect and onset scans — and what a report reads
// from it.
#pragma once

#include <absl/status/statusor.h>

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "insdiag/engine/analysis.h"
#include "insdiag/engine/filter/epoch_run.h"
#include "insdiag/engine/filter/forward_filter.h"
#include "insdiag/engine/filter/smoother.h"
#include "insdiag/engine/finder/onset_scan.h"
#include "insdiag/engine/finder/score_test.h"
#include "insdiag/engine/finder/warm_up_scan.h"
#include "insdiag/engine/model/state_layout.h"
#include "insdiag/engine/monitor/monitoring.h"

namespace insdiag::engine::pipeline {

// One run of a model through the filter, the smoother and the monitor — and,
// when asked, the missing-effect scan.
struct ModelPass {
  ErrorModel model;
  std::unique_ptr<StateLayout> layout;
  ForwardPass forward;
  SmoothedPass smoothed;
  MonitorResult monitor;
  std::unique_ptr<ScoreTestObserver> scan;
  std::vector<OnsetFit> onsets;  // the fault terms' scan, with `scan`
  std::vector<WarmUpFit> warm_ups;  // each absent warm-up's scan over time constants, with `scan`
  std::vector<std::string> segment_motion;
  // The innovations' log-likelihood with every added constant effect at its
  // maximum-likelihood value (the profile likelihood), see ProfileCorrection.
  double log_likelihood = 0.0;
};

absl::StatusOr<ModelPass> RunPass(const BenchRun& run, const EpochRun& epochs, const ErrorModel& model,
                                  const SampleScreening& samples, const AnalysisOptions& options,
                                  bool with_scan);

// ModelPass::log_likelihood alone, from the forward filter: for a model that
// is only compared, not reported (no smoother, no monitor).
absl::StatusOr<double> ProfileLogLikelihood(const EpochRun& epochs, const ErrorModel& model);
// The same from a forward pass of `model` already run.
double ProfileLogLikelihood(const ForwardPass& forward, const ErrorModel& model);

// The prior σ of an effect added at a scan's estimate: wide against it,
// `estimated_prior_scale` × the larger of |estimate| and 3 SE.
double PriorSigmaAroundEstimate(double estimate, double std_error, const AnalysisOptions& options);

// A fault effect `term` from `onset_s`, its prior wide against a scan's
// estimate and SE of it (PriorSigmaAroundEstimate).
ModelEffect FaultEffectAt(const EffectTerm& term, double onset_s, double estimate, double std_error,
                          const AnalysisOptions& options);

// The report's fit of a pass: verdict, channels, NIS, likelihood, criteria.
void FillFit(const ModelPass& pass, const BenchRun& run, const AnalysisOptions& options, AnalysisReport& r);

// The added constant effects' estimates: the final filtered states (constants
// keep their value, so the last epoch's estimate is the smoothed one).
// RMS over the run of a constant term's regressor, per parameter, on the
// measured inputs (what the filter's columns use), or, given them, on what a
// perfect unit would have measured on the table (ReferenceMeasurements): what
// the test excited; with `full_scale`, on the reference inputs' magnitudes
// (each sensor's |ω| and |f| on every axis): what the regressor would be with
// the whole input along its axis. A run's segment starts are left out (their
// samples cover unrecorded moves).
std::array<double, 2> RegressorRms(const BenchRun& run, const EffectTerm& term,
                                   const std::vector<std::array<double, 6>>* reference_inputs = nullptr,
                                   bool full_scale = false);

// Each warm-up's start value, from the smoothed state at the first epoch:
// what the whole run says of it, where the scan that found it measured it to
// first order only.
std::vector<ParameterEstimate> WarmUpEstimates(const ModelPass& pass);

// The constant effects' estimates at the end of the pass, each with its
// observability (parameter_estimate.h): the prior it is judged against is the
// model's diffuse prior rescaled to what the table excited, so that an axis
// excited only by its own noise is not observable.
// `reference_measurements`: ReferenceMeasurements(run).
std::vector<ParameterEstimate> ConstantEffectEstimates(const ModelPass& pass, const BenchRun& run,
                                                       const std::vector<std::array<double, 6>>& reference_measurements);

// Measured, predicted, residual, ±σ and the sensor states per epoch.
void FillSeries(const ModelPass& pass, AnalysisSeries& series);

}  // namespace insdiag::engine::pipeline
