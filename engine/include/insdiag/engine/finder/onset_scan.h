// Bias steps and ramps at an unknown onset: the generalised likelihood ratio
// over every onset, from one filter pass (Willsky & Jones, "A generalized
// likelihood ratio approach to the detection and estimation of jumps in
// linear systems", IEEE Trans. AC 21(1), 1976).
//
// A fault that starts at the beginning of update interval θ adds W_k β to
// the navigation errors over every interval k ≥ θ, where W_k is the
// interval's column for a unit fault (model_transitions.h, FaultColumn): a
// step's μ_0, a ramp's μ_1 + (t_start + Δt/2 − t₀) μ_0 of its sensor axis.
// As in the score test (score_test.h) the filter, which does not know of the
// fault, turns it into an innovation mean X_k β, with
//   A_k = F_k A_{k−1} + W_k,  X_k = H̃_k A_k,  F_k = Φ_k L_{k−1}
// where L_k = Π_c (I − K_c h_c) is the epoch's sequence of scalar updates and
// row c of H̃_k is h_c Π_{c'<c} (I − K_c' h_c'). Its score and information
//   s(θ) = Σ_{k≥θ} X_kᵀ S_k⁻¹ ν_k,   I(θ) = Σ_{k≥θ} X_kᵀ S_k⁻¹ X_k
// for every θ at once come from one backward sweep of the adjoint
//   λ_k = H̃_kᵀ S_k⁻¹ ν_k + F_{k+1}ᵀ λ_{k+1}          (innovations seen from k on)
//   Γ_k = H̃_kᵀ S_k⁻¹ H̃_k + F_{k+1}ᵀ Γ_{k+1} F_{k+1}    (their information)
//   m_k = F_{k+1}ᵀ (Γ_{k+1} W_{k+1} + m_{k+1})
//   s(θ) = s(θ+1) + W_θᵀ λ_θ
//   I(θ) = I(θ+1) + W_θᵀ Γ_θ W_θ + W_θᵀ m_θ + m_θᵀ W_θ
//   Cov(s(θ), s(θ+1)) = I(θ+1) + W_θᵀ m_θ
// (the gains are rebuilt from the stored covariances: they do not depend on
// the data). Per sensor axis, the step's and the ramp's columns share one
// pair Z = [μ_0, μ_1 + (t_start + Δt/2 − t_c) μ_0] (t_c the run's middle, for
// conditioning); a ramp from t₀ is Z v with v = (t_c − t₀, 1).
//
// At each onset T(θ) = s(θ)² / I(θ) is the likelihood ratio 2Δℓ of the
// fault with its magnitude at the maximum, β̂ = s/I, SE 1/√I. Its maximum
// over the onsets is not χ²(1): the p-value is Davies' bound for the
// maximum of a χ²(1) process (Davies, Biometrika 74(1), 1987; Rice's
// up-crossing formula, Bell Syst. Tech. J. 23, 1944),
//   P(max T > u) ≤ P(χ²₁ > u) + V e^{−u/2} / π,
// with V the length of the path the standardised score traces over the
// onsets, Σ_θ arccos ρ(θ, θ+1), ρ the correlation of successive scores.
// The onset: the median interval of its posterior under flat priors on the
// onset and the magnitude, weights ∝ e^{T(θ)/2} I(θ)^{−1/2} (the likelihood
// integrated over the magnitude; Smith, "A Bayesian approach to inference
// about a change-point in a sequence of random variables", Biometrika 62(2),
// 1975). The onset is then placed where, in that interval or the one before,
// the likelihood ratio of a fault whose first interval holds only its share
// after the onset is largest (the same recursion with that share of the
// interval's column, model_transitions.h FaultColumn): at the sample
// boundaries, then at 1/16 of a sample either side of the best, since a
// fault that begins inside a sample gives that sample's interval mean its
// share. The magnitude is the one there. The posterior's standard deviation
// and central interval are taken over every onset tried, the intervals'
// starts and the samples and sixteenths about the placed onset, each
// spread over its cell (halfway to its neighbours): an onset placed within a
// sample gets an interval as narrow as the run allows, not an epoch's start;
// the interval is widened to hold the placed onset. Where a still stretch
// hides the sensor axis the likelihood is flat in the onset, and the interval says so. Two faults
// whose innovation signatures from one fault's onset are nearly parallel in the S⁻¹ metric,
// |I_ab(θ)|/√(I_aa(θ) I_bb(θ)) above a threshold, cannot be told apart by the run (on a still,
// level table a gyro's step about x tilts the unit as an accelerometer's ramp on y does): the fault
// names the other, as the score test's look-alikes do. Each fit that could be
// a finding also gets the filter's peak attitude error under it, from one
// forward sweep of A_k for those fits at their onsets: on a still table a z gyro's step turns the
// heading and, through Earth rate, tilts the unit as a y gyro's ramp does, but a step big enough to
// match the ramp turns the heading by radians, where the first-order model that makes the two alike
// no longer holds.
#pragma once

#include <optional>
#include <vector>

#include "insdiag/engine/filter/epoch_run.h"
#include "insdiag/engine/filter/forward_filter.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/model/state_layout.h"

namespace insdiag::engine {

struct OnsetScanOptions {
  // Onsets are tried where the run holds at least this much on either side:
  // a jump in the first seconds is the turn-on bias, one in the last cannot
  // be told from noise.
  double min_side_s = 60.0;
  // Each tail of the onset's posterior left outside its interval (0.16: ±1σ).
  double interval_tail = 0.16;
  // |cos| of two faults' signatures at one's onset above which it names the other.
  double ambiguity_threshold = 0.9;
  // The family-wise level at which a fault is a finding (as the finder's):
  // a fit whose p-value is above it is none whatever its linear range, and
  // its peak attitude error is not swept.
  double family_wise_alpha = 0.01;
};

// The best onset of one fault term.
struct OnsetFit {
  EffectTerm term;           // gyro_bias_step.x, acc_bias_ramp.z, …
  bool identifiable = false;  // false: the run carries no information on it
  int onset_epoch = -1;       // the first update interval with the fault (posterior median)
  double onset_s = 0.0;       // the onset: within a sample, in or before that interval (header)
  double onset_std_s = 0.0;   // the posterior's standard deviation
  double onset_low_s = 0.0, onset_high_s = 0.0;  // its central interval
  double statistic = 0.0;     // max over onsets of T = 2Δℓ
  double p_value = 1.0;       // Davies' bound over the onsets tried
  double estimate = 0.0;      // β̂ at the onset, in the family's unit
  double std_error = 0.0;
  double path_length = 0.0;   // V
  int onsets_tried = 0;
  // The filter's peak attitude error under the fault at its estimate and
  // onset, |β̂| max_k |A_ψ,k| (A_k of the header, after each prediction):
  // how far the estimate is from the first-order model's range (linear_range.h).
  double peak_attitude_error_rad = 0.0;
  std::vector<EffectTerm>
      ambiguous_with;  // faults whose signature from this onset is nearly parallel
  // The profile the best onset is taken from: T(θ) at every onset tried,
  // from `first_onset_epoch` on.
  int first_onset_epoch = 0;
  std::vector<double> statistic_by_onset;
  // β̂ and its standard error with the onset at each epoch of the run (0
  // where the run holds no information on it), tried or not: what the
  // navigation errors say of a fault at an onset found elsewhere.
  std::vector<double> estimate_by_epoch, std_error_by_epoch;
};

// T = 2Δℓ of `fit`'s term with its onset given rather than searched, at
// `onset_s`: the first update interval that starts at or after it. nullopt
// where no onset was tried there.
std::optional<double> StatisticWithOnsetAt(const OnsetFit& fit, const EpochRun& run,
                                           double onset_s);
// β̂ and its standard error with the onset at the epoch nearest `onset_s`,
// within `tolerance_s` of it (an onset known to that precision); nullopt
// where the run holds no information there.
struct EstimateAtOnset {
  double onset_s = 0.0;
  double estimate = 0.0;
  double std_error = 0.0;
};
std::optional<EstimateAtOnset> EstimateNearOnset(const OnsetFit& fit, const EpochRun& run, double onset_s,
                                                 double tolerance_s);

// Davies' bound on P(max over onsets of 2Δℓ ≥ statistic) for a scan whose
// path length is `path_length` (the p-value of OnsetFit).
double OnsetPValue(double statistic, double path_length);

// Every fault term of the catalogue absent from `model`.
std::vector<EffectTerm> AbsentFaultTerms(const ErrorModel& model);

// The scan of `terms` (fault terms) over the forward pass `forward` of the
// model laid out by `layout` on the condensed run `run`.
std::vector<OnsetFit> ScanOnsets(const ForwardPass& forward, const StateLayout& layout, const EpochRun& run,
                                 const std::vector<EffectTerm>& terms, const OnsetScanOptions& options);

}  // namespace insdiag::engine
