// Localisation of a failure to a sensor: which sensor state jumped, and when.
//
// For each sensor state i and onset epoch e, the hypothesis "x_i jumped by ν
// just before epoch e" changes the innovations after e by X_k ν, where X_k is
// the innovation's sensitivity to the jump propagated through the filter's own
// gains (the filter does not know of the jump and partly absorbs it):
//   A_e = e_i;   per scalar update: X = h A,  A ← A − K X;   per interval: A ← Φ A
// The generalized likelihood ratio of the jump (Willsky & Jones, "A
// generalized likelihood ratio approach to the detection and estimation of
// jumps in linear systems", IEEE Trans. AC 21(1), 1976) is
//   ℓ_i(e) = (Σ X S⁻¹ ν)² / Σ X S⁻¹ X  ~ χ²(1) without a jump,
// with the jump's estimate ν̂ = Σ X S⁻¹ ν / Σ X S⁻¹ X and σ(ν̂) = (Σ X S⁻¹ X)^{-1/2}.
// The state and onset of the largest ℓ name the faulty sensor; the gains are
// rebuilt from the stored covariances (they do not depend on the data).
// Under ν̂ the filter's attitude error would peak at |ν̂| max_k ‖A_ψ,k‖ over
// the window (A's attitude rows): a jump that puts it beyond a radian is an
// artefact of the first-order model, not a localisation (filter/linear_range.h).
#pragma once

#include <string>
#include <vector>

#include "insdiag/engine/filter/forward_filter.h"
#include "insdiag/engine/model/state_layout.h"

namespace insdiag::engine {

struct JumpHypothesis {
  std::string state;  // e.g. "gyro_bias_gm.x"
  double onset_s = 0.0;
  double statistic = 0.0;  // ℓ
  double p_value = 0.0;    // family-wise over the states and onsets tried
  double jump = 0.0;       // ν̂ in the state's unit
  double jump_std_error = 0.0;
  double peak_attitude_error_rad = 0.0;  // under ν̂, over the window
};

struct LocalisationOptions {
  double onset_search_before_s = 90.0;  // onsets tried before the first flagged epoch …
  double onset_search_after_s = 30.0;   // … and after it
  double window_s = 120.0;              // innovations used after each onset
};

// Jump hypotheses for every sensor state around `flagged_s`, most likely first.
std::vector<JumpHypothesis> LocaliseJump(const ForwardPass& forward, const StateLayout& layout, double flagged_s,
                                         const LocalisationOptions& options);

}  // namespace insdiag::engine
