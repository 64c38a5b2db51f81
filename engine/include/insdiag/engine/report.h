// The analysis report: what the engine says about one bench run under one
// error model. A plain value; the server and the CLI map it onto the
// insdiag.v1.AnalysisReport message (shared/spec/cli-and-report.md).
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "insdiag/engine/decision.h"
#include "insdiag/engine/ident/allan.h"
#include "insdiag/engine/parameter_estimate.h"
#include "insdiag/engine/ident/correlation.h"
#include "insdiag/engine/monitor/monitoring.h"

namespace insdiag::engine {

// Where in the run a candidate effect shows: its share of the score statistic
// per channel and time segment.
struct SegmentContribution {
  std::string channel;
  double start_s = 0.0;
  double end_s = 0.0;
  std::string motion;  // what the table did: "still", "turning", "tilting"
  double share = 0.0;  // fraction of the candidate's statistic
};

// A catalogue effect absent from the model, tested from the same pass.
struct EffectCandidate {
  std::string name;  // "gyro_scale_factor.z" (or a family name in family_candidates)
  std::string family;
  // "SCORE" (Lagrange-multiplier test), "STRUCTURE" (correlation-function
  // family), "LIKELIHOOD" (a bias random walk or second-order pair by the
  // innovations' likelihood), "GLR" (a bias step or ramp at an unknown
  // onset: the generalised likelihood ratio over onsets, finder/onset_scan.h)
  // or "RAW" (a jump or ramp the still segments' raw samples show: its
  // p-value is their test's, its statistic what the navigation errors give it at that
  // onset; finder/fault_findings.h)
  std::string source;
  double statistic = 0.0;
  int dof = 0;
  double p_value = 1.0;
  double p_value_holm = 1.0;
  double estimate = 0.0;  // in the family's unit (shared/spec/effects.md)
  double std_error = std::numeric_limits<double>::quiet_NaN();
  std::string unit;
  // false: not a finding of this run, and `note` says why: the run's motion
  // or temperature cannot excite it, its one-step estimate is far outside the
  // filter's linear range, or the still segments' raw samples refute it
  // (finder/effect_finder.h).
  bool identifiable = true;
  // false: no test of it ran on this model (a random structure the scan
  // left for a later model; `note` says why). Its p-value is 1 and it counts
  // in no family-wise correction.
  bool tested = true;
  double predicted_delta_aic = 0.0;
  double predicted_delta_bic = 0.0;
  std::vector<std::string> correlated_with;  // candidates it cannot be told apart from in this run
  std::vector<SegmentContribution> where;
  std::string note;  // e.g. why it is not identifiable
  // Fault effects (source "GLR" or "RAW"): the onset [s of run time], its
  // posterior standard deviation and central interval (for "RAW", the
  // tolerance the raw samples place it to).
  std::optional<double> onset_s;
  double onset_std_s = 0.0;
  double onset_low_s = 0.0;
  double onset_high_s = 0.0;
  // Fault effects: the change of the unit the fault asks for, in its sensor
  // axis's drift σ (a step's size, a ramp's reach by the run's end), which
  // orders the look-alikes the run cannot tell apart when the raw samples show
  // neither (fault_findings.h).
  std::optional<double> size_in_drift_sigma;
  // Warm-ups (finder/warm_up_scan.h): the time constant at the scan's best [s].
  std::optional<double> time_constant_s;
  // Fault effects: the sensor axis's raw samples in the static segments show
  // the same change near the onset (finder/fault_findings.h, RawSampleChange).
  bool seen_in_raw_samples = false;

  // Tested, identifiable and significant at family-wise `alpha` (Holm).
  bool SignificantAt(double alpha) const { return identifiable && tested && p_value_holm < alpha; }
};

// Correlation processing of one drift state's smoothed estimate.
struct DriftCorrelation {
  std::string state;  // e.g. "gyro_bias_gm.x"
  Sensor sensor = Sensor::kGyro;
  int axis = 0;
  ident::CorrelationAnalysis analysis;
};

struct ChannelComparison {
  std::string name;
  ChannelFit before;
  ChannelFit after;
};

// How well a model fits a run: the mean NIS, the innovations' (profile)
// log-likelihood ℓ and the information criteria on it, AIC = 2k − 2ℓ
// (Akaike, IEEE Trans. AC 19(6), 1974) and BIC = k ln N − 2ℓ (Schwarz,
// Ann. Stat. 6(2), 1978), k the model's parameters and N its scalar updates.
struct FitMetrics {
  double nis_mean = 0.0;
  double log_likelihood = 0.0;
  double aic = 0.0;
  double bic = 0.0;
};

// Model B (this report's) against model A on the same run.
struct ModelComparison {
  std::vector<std::string> baseline_effects;  // A
  std::vector<std::string> added_effects;     // B = A + these
  std::vector<ChannelComparison> channels;
  FitMetrics before;  // A
  FitMetrics after;   // B
  double realized_lr = 0.0;   // 2 (logL_B − logL_A)
  double predicted_lr = 0.0;  // model A's score statistic for the added effects
};

struct DiscoveryStep {
  int step = 0;
  std::string effect;
  double estimate = 0.0;
  double std_error = 0.0;
  std::string unit;
  double statistic = 0.0;
  double p_value = 0.0;
  FitMetrics fit;  // of the model after the step
  std::vector<ChannelFit> channels;
  std::vector<ParameterEstimate> estimates;  // of the added terms, after the step
};

struct AnalysisReport {
  Verdict verdict = Verdict::kGood;
  std::vector<std::string> model_effects;
  int parameter_count = 0;
  std::vector<ChannelFit> channels;
  FitMetrics fit;
  // The band the mean NIS of a model that holds lies in (at the family-wise level).
  double nis_band_low = 0.0;
  double nis_band_high = 0.0;
  int scalar_updates = 0;
  double gamma2 = 0.0;
  double eta2 = 0.0;
  std::vector<FaultInterval> faults;
  // Where the bench moved against its reference (monitor/bench_motion.h).
  std::vector<BenchMotion> bench_motion;
  std::vector<Localisation> localisation;   // the sensor behind each gradual failure
  std::vector<Localisation> discrepancies;  // forward/backward disagreements per sensor state
  std::vector<EffectCandidate> effect_candidates;  // per term, most significant first
  std::vector<EffectCandidate> family_candidates;  // per family
  std::vector<ParameterEstimate> identified;
  // The verdict in plain words, what a quality engineer reads first
  // (plain_words.h); the notes below are the engine's detail.
  std::vector<std::string> plain_words;
  std::vector<std::string> notes;  // what the engine wants the user to know (e.g. a fallback it took)
  // What the analysis decided, as data; each decision's note is among `notes`.
  std::vector<Decision> decisions;
  std::vector<DriftCorrelation> correlation;
  std::optional<ident::AllanResult> allan;
  std::optional<ModelComparison> comparison;
  std::vector<DiscoveryStep> discovery;
  double duration_s = 0.0;
  size_t samples = 0;
  double sample_rate_hz = 0.0;
  double update_interval_s = 0.0;
};

// Per-epoch series for plotting (`insdiag analyze --series`).
struct AnalysisSeries {
  std::vector<double> time_s;
  // K × kChannelCount (filter/observation.h); a channel not observed at an
  // epoch has σ = 0 and ν = 0 there, and its window ratio is NaN where its
  // window holds no observation.
  Eigen::MatrixXd measured;   // z
  Eigen::MatrixXd predicted;  // h x⁻
  Eigen::MatrixXd residual;   // ν
  Eigen::MatrixXd sigma;      // α = √(h P hᵀ + r)
  Eigen::MatrixXd window_ratio;  // moving F
  std::vector<std::string> state_names;  // sensor states
  Eigen::MatrixXd forward, smoothed, smoothed_sigma, backward, discrepancy;  // K × m
};

}  // namespace insdiag::engine
