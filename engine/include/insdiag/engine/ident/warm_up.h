// A bias that settles after power-up, measured from the run's still start
// and removed before identification, like the dominant constants
// (static_constants.h).
//
// A unit switched on for its test warms by kelvins over its first minutes
// and its biases follow (IEEE Std 952-1997, §B.8: "warm-up"), b(t) = b_w
// e^{−t/τ_w} from power-up. The base model's drift, a first-order
// Gauss–Markov process of σ and τ, follows such a transient only where τ_w is
// near τ, and only from a start the filter grants (filter/start_departure.h):
// a MEMS part's warm-up of 0.1 °/s settling in a minute under a drift of
// minutes is a misfit on every channel the bias reaches for as long as it
// lasts.
//
// Over the still start, where the reference holds the body at one attitude
// and the bench is quiet (before monitor/bench_motion.h finds it moving), a
// perfect unit reads Earth's rate and gravity (static_constants.h); the
// reading less that, averaged over each update interval, is fitted by least
// squares as c + b e^{−t/τ_w} for τ_w on a logarithmic grid from three update
// intervals to a third of the still start (a transient that settles within
// it), c and b linear at each τ_w. A transient is the unit's warm-up where b
// refutes the stationary model: b² > χ²₁(1 − α/6) Var(b), family-wise α
// over the six axes (Bonferroni), Var(b) = wᵀΣw for b = wᵀȳ, Σ the
// covariance of the interval means under the a-priori model (its white
// noise N²/Δ and its first-order Gauss–Markov drift σ² e^{−|Δt|/τ}). A
// stationary drift starts at N(0, σ²) and wanders by σ over τ, so its
// transients are of size σ; many σ is a start no stationary drift holds. So is a random walk's
// (effects.md, `*_bias_rw`): it wanders from its start as far as it ends
// from it: a transient e^{−(T−t)/τ′} ending at the still start's end,
// fitted beside the start's, refutes stationarity as strongly. A warm-up is
// the power-up's alone: only a start that departs while the end does not
// (the end transient's statistic below the same threshold) is one. The transient is
// removed from every sample of the axis and reported with its τ_w.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/model/error_model.h"
#include "insdiag/engine/parameter_estimate.h"

namespace insdiag::engine::ident {

struct WarmUpOptions {
  double family_wise_alpha = 0.01;
  // Grid of τ_w: points per decade, from `shortest_intervals` update intervals
  // to `longest_share` of the quiet still start.
  int grid_per_decade = 8;
  double shortest_intervals = 3.0;
  double longest_share = 1.0 / 3.0;
};

// One sensor axis' warm-up, fitted on the still start.
struct WarmUp {
  int axis = 0;            // sensor axis (SensorAxisIndex)
  double amplitude = 0.0;  // b_w at the run's first sample [rad/s | m/s²]
  double std_error = 0.0;  // SE(b_w) from the white noise alone
  double tau_s = 0.0;      // τ_w
  double statistic = 0.0;      // b² / Var(b) under the stationary model
  double end_statistic = 0.0;  // the same of a transient ending at the still start's end, fitted beside it
  bool significant = false;
};

// The best transient of every axis on the still start of `run` (before the
// bench first moves at `bench_moved_from_s`); empty when the quiet still
// start is shorter than three grid points' worth.
std::vector<WarmUp> FitWarmUps(const BenchRun& run, const ErrorModel& a_priori, double update_interval_s,
                               double still_tolerance_rad, std::optional<double> bench_moved_from_s,
                               const WarmUpOptions& options = {});

// Fits the warm-ups, removes the significant ones from every sample of
// `run`, says so in `notes` and returns them as identified parameters
// ({gyro|acc}_warm_up.{x|y|z} and its .tau, method STATIC).
std::vector<ParameterEstimate> RemoveWarmUps(BenchRun& run, const ErrorModel& a_priori, double update_interval_s,
                                             double still_tolerance_rad, std::optional<double> bench_moved_from_s,
                                             const WarmUpOptions& options, std::vector<std::string>& notes);

}  // namespace insdiag::engine::ident
