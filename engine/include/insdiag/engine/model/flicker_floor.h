// A bias-instability (flicker) floor as states the filter can carry.
//
// Flicker rate noise, S(f) ∝ 1/f, has the flat Allan variance
//   σ²(τ) = (2 ln 2/π) B²                         (IEEE Std 952-1997, Annex C)
// and no finite-state model. A 1/f spectrum is a superposition of
// Lorentzians whose correlation times are spread uniformly in log T
// (van der Ziel, Physica 16, 1950; Keshner, Proc. IEEE 70(3), 1982), so over
// the span of cluster times [τ_min, τ_max] where the floor stands it is
// carried as n first-order Gauss–Markov processes (seed eq. 5)
//   T_j = (τ_min / u*) r^j,  j = 0 … n−1,  n the least with u* T_{n−1} ≥ τ_max,
// u* ≈ 1.89 the cluster time of a process's Allan peak per unit T
// (model/gauss_markov_allan.h), r = 10^{3/2}, all of one σ_c, with
//   σ_c² = (2 ln 2/π) B² / exp( mean over log-spaced τ in [τ_min, τ_max] of ln Σ_j g(τ/T_j) ):
// the sum's Allan variance equals the floor's in the mean of its logarithm
// over the span. The components are states of their own, beside the axis'
// Gauss–Markov drift (the model's `bias`), which carries what the unit's
// drift shows beyond the floor. At r = 10^{3/2} the sum's Allan deviation ripples within
// about ±7 % of the floor, inside an Allan point's 1σ interval until it holds
// some 200 independent differences; a ratio of 10² would ripple ±18 %.
#pragma once

#include <numbers>
#include <vector>

#include "insdiag/engine/model/error_model.h"

namespace insdiag::engine {

// (2 ln 2/π): the Allan variance of flicker rate noise per B² (IEEE 952 Annex C).
inline constexpr double kFlickerAllanVariancePerB2 = 2.0 * std::numbers::ln2 / std::numbers::pi;

// The components of `floor` in increasing T, 0 … n−1 (empty for no floor).
std::vector<GaussMarkov> FlickerComponents(const FlickerFloor& floor);

// n of the equation above, without computing σ_c (0 for no floor).
int FlickerComponentCount(const FlickerFloor& floor);

// The floor standing over [shortest_tau_s, longest_tau_s] where flicker of
// coefficient B reaches above white noise of density N: from where
// N²/τ = (2 ln 2/π) B² (IEEE 952 Annex C), or the span's start if later.
// No floor (B = 0) when it is nowhere above.
FlickerFloor FlickerFloorAbove(double coefficient, double white_density, double shortest_tau_s,
                               double longest_tau_s);

// Component `component` of the floor on `sensor`'s axis `axis` in `model`.
GaussMarkov FlickerComponentOf(const ErrorModel& model, Sensor sensor, int axis, int component);

}  // namespace insdiag::engine
