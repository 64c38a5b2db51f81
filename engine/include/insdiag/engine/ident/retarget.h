// Retargeting of the error model's parameters (the seed's "retargeting of
// parameters of the error model"): the filter runs with the a-priori model,
// the identification tells the unit's actual parameters, and the model is
// re-tuned with them until they settle.
//
//   drifts     σ, τ of each base Gauss–Markov drift from correlation processing
//              of its smoothed estimate (correlation.h), where the run resolves it
//   noise      angle / velocity random walk and quantisation from the Allan fit
//              of the static segments (allan.h), where resolved
//   reference  a channel group whose innovations are larger than predicted —
//              covariance matching, r̂ = mean(ν²) − mean(h P hᵀ) (Mehra,
//              "Approaches to adaptive filtering", IEEE Trans. AC 17(5), 1972) —
//              is flagged for a maximum-likelihood fit of its observation noise
//              (analysis): the unit moved in ways the bench's reference did not
//              record
#pragma once

#include <absl/status/statusor.h>

#include <algorithm>
#include <array>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "insdiag/engine/filter/forward_filter.h"
#include "insdiag/engine/filter/observation.h"
#include "insdiag/engine/filter/smoother.h"
#include "insdiag/engine/ident/allan.h"
#include "insdiag/engine/ident/correlation.h"
#include "insdiag/engine/model/error_model.h"
#include "insdiag/engine/parameter_estimate.h"
#include "insdiag/engine/report.h"

namespace insdiag::engine::ident {

// Smoother options that also compute the error autocovariance the
// correlation processing of the base drifts needs.
SmootherOptions DriftSmootherOptions(const ErrorModel& model, const StateLayout& layout, const ForwardPass& forward,
                                     const CorrelationOptions& options);

// Correlation processing of every base drift state of a smoothed pass.
std::vector<DriftCorrelation> CorrelateDrifts(const ForwardPass& forward, const SmoothedPass& smoothed,
                                              const StateLayout& layout, const CorrelationOptions& options,
                                              std::vector<std::string>* notes);

struct RetargetResult {
  ErrorModel model;
  std::vector<ParameterEstimate> identified;  // ACF estimates of the resolved drifts
  bool settled = true;  // no parameter moved by more than the tolerance
};

// σ and τ of every resolved drift from its exponential fit, reported; the
// model takes them only where the data reject the a-priori pair — the Wald
// statistic of (ln σ₀, ln τ₀) against the fit's covariance beyond χ²₂(1 − α)
// — so that a model the data do not contradict stays as it was. Settled when
// every change is below `settle_log_ratio` in log or below one standard error.
RetargetResult RetargetDrifts(const ErrorModel& current, const ErrorModel& a_priori,
                              const std::vector<DriftCorrelation>& drifts, double settle_log_ratio, double alpha);

// White-noise densities and quantisation from the Allan fit where resolved
// and where the fit rejects the a-priori value (Wald statistic beyond
// χ²₁(1 − α), as for the drifts); returns the estimates it used (method ALLAN).
std::vector<ParameterEstimate> ApplyAllanNoise(const AllanResult& allan, const ErrorModel& a_priori,
                                               ErrorModel& model, double alpha);

// The channel groups (kReferenceChannelGroups) whose innovations exceed their predicted variance
// beyond the χ² band at `alpha` and are not positively correlated (a missing
// effect, not a missing noise), each with the reference σ covariance
// matching gives it: σ² + mean(ν² − S) (Mehra, IEEE Trans. AC-15(2), 1970).
// That moment estimate is biased high where the filter's gain on the
// reference is near one (a jitter enters two successive innovations), so the
// analysis takes it as the upper end of a likelihood search, not as the value.
// The reference's channels in the groups that share one σ of its accuracy
// (model/error_model.h): position and velocity, across and along the vertical.
struct ReferenceChannelGroup {
  std::string_view name;
  std::string_view unit;
  double ReferenceAccuracy::*sigma;
  int first_channel;
  int channel_count;
};
inline constexpr std::array<ReferenceChannelGroup, 4> kReferenceChannelGroups = {{
    {"horizontal position", "m", &ReferenceAccuracy::horizontal_position_sigma_m, kPositionChannel, 2},
    {"vertical position", "m", &ReferenceAccuracy::vertical_position_sigma_m, kPositionChannel + 2, 1},
    {"horizontal velocity", "m/s", &ReferenceAccuracy::horizontal_velocity_sigma_mps, kVelocityChannel, 2},
    {"vertical velocity", "m/s", &ReferenceAccuracy::vertical_velocity_sigma_mps, kVelocityChannel + 2, 1},
}};

// Per group of kReferenceChannelGroups, the σ covariance matching gives
// where that group's innovations exceed their band.
struct ReferenceNoiseExcess {
  std::array<std::optional<double>, kReferenceChannelGroups.size()> matched_sigma;
  bool Any() const {
    return std::any_of(matched_sigma.begin(), matched_sigma.end(),
                       [](const std::optional<double>& s) { return s.has_value(); });
  }
};
ReferenceNoiseExcess ScreenReferenceNoise(const ForwardPass& forward, double alpha,
                                          const ErrorModel& model);

// Noise terms of an Allan-based a-priori model (ErrorModelFromAllan) that the
// Allan fit did not resolve and that were set from bounds: the white density
// from the tangent bound min σ̂√τ (an upper bound: σ²(τ) ≥ N²/τ), the drift
// from the curve's lowest point (also an upper bound) when no drift term
// (Markov, B or K) was resolved.
struct UnresolvedNoise {
  std::array<bool, 3> gyro_white = {false, false, false};
  std::array<bool, 3> acc_white = {false, false, false};
  std::array<bool, 3> gyro_drift = {false, false, false};
  std::array<bool, 3> acc_drift = {false, false, false};
  // Drift σ seeded by a resolved Allan term (Markov, or the constructions
  // from B or K). The Allan fit of the static segments only seeds the
  // drift (analysis.cc): correlation processing of the whole run identifies
  // it where it resolves it, and nothing else re-tunes it.
  std::array<bool, 3> gyro_drift_seed = {false, false, false};
  std::array<bool, 3> acc_drift_seed = {false, false, false};
  // White densities the Allan fit resolved. They too are seeds: the raw
  // samples of a unit that rocks or sways carry the motion its gyros
  // measured, which the Allan curve reads as noise and the filter's
  // innovations do not show.
  std::array<bool, 3> gyro_white_seed = {false, false, false};
  std::array<bool, 3> acc_white_seed = {false, false, false};

  bool Any() const;
};
UnresolvedNoise UnresolvedAllanTerms(const AllanResult& allan);

struct NoiseScaleOptions {
  // Search range of each group's scale, relative to the bound it starts from.
  // The bounds are upper bounds, so the scale stays at or below one; three
  // decades below is beyond any bound the Allan curve of a bench run leaves.
  double min_scale = 1e-3;
  double max_scale = 1.0;
  // Golden-section search stops when the bracket of ln s is this narrow.
  // Seeded drifts were resolved by the Allan fit and may need to rise: their
  // range reaches this far above the seed.
  double max_seed_scale = 10.0;
  // Golden-section search stops when the bracket of ln s is this narrow
  // (5%: well inside the scale's standard error on any bench run).
  double log_tolerance = 0.05;
  // Coordinate sweeps over the groups (the groups interact weakly: white
  // gyro noise shows in the attitude, white accelerometer noise in velocity).
  int sweeps = 2;
};

struct NoiseScaleGroup {
  std::string name;      // "gyro white", "acc white", "gyro drift", "acc drift", "gyro drift seed", "acc drift seed"
  std::vector<std::string> terms;  // e.g. "gyro_arw.x", "gyro_bias_gm.z.sigma"
  double scale = 1.0;    // ŝ: the terms' new values are ŝ × their bounds
  double log_std_error = std::numeric_limits<double>::quiet_NaN();  // SE of ln ŝ (observed information)
  bool at_limit = false;  // ŝ on the search range's edge (no interior maximum)
};

struct NoiseScaleResult {
  ErrorModel model;
  std::vector<NoiseScaleGroup> groups;
  std::vector<ParameterEstimate> identified;  // method "ML", one per re-tuned term
  double log_likelihood_before = 0.0;
  double log_likelihood_after = 0.0;
  int filter_passes = 0;
};

// Maximum-likelihood re-tuning of the noise terms set from bounds: one common
// scale s per group (white gyro, white accelerometer, drift σ of gyros, of
// accelerometers — only the flagged axes), multiplying the densities (and the
// drift σ), chosen to maximise the forward filter's innovation log-likelihood
//   ℓ(s) = −½ Σ_k [ln(2π S_k(s)) + ν_k(s)²/S_k(s)]
// (prediction-error decomposition: Schweppe, IEEE Trans. IT-11(1), 1965;
// noise identification by maximum likelihood: Mehra, IEEE Trans. AC-15(2),
// 1970; Shumway & Stoffer, Time Series Analysis and Its Applications, 4th
// ed., §6.3). Each scale is found by golden-section search on ln s (Kiefer
// 1953; Press et al., Numerical Recipes, 3rd ed., §10.2), the groups in turn;
// its standard error is 1/√(−∂²ℓ/∂(ln s)²) from a central second difference
// at the maximum (observed Fisher information). The terms that were
// resolved keep their values.
absl::StatusOr<NoiseScaleResult> ScaleUnresolvedNoise(const EpochRun& run, const ErrorModel& model,
                                                      const UnresolvedNoise& which, const NoiseScaleOptions& options = {});

}  // namespace insdiag::engine::ident
