// Whether a candidate's estimate lies within the first-order error model's
// range (docs/IDENTIFICATION.md, "The scan's linear range").
//
// Under an estimate β̂ the filter's attitude error would peak at ψ (the
// attitude rows of the candidate's response in the filter, after each
// prediction: score_test.h for the constant terms, onset_scan.h for the
// faults, fault_localisation.h for the monitor's jumps). The first-order
// attitude model C̃ = (I − [ψ×]) C drops [ψ×]²/2, a relative error of ψ/2 in
// the innovations' mean and so in β̂.
// - ψ/2 above one half (ψ > 1 rad): the linear model no longer describes the
//   filter and the estimate is an artefact, not a finding;
// - ψ/2 above the estimate's relative standard error only: the linearisation,
//   not the noise, limits the estimate.
// Either way the estimate's test counts ψ/2 of it as an error beside its
// noise (StandardErrorWithLinearisation), so that a term the linear model
// overstates is not a finding because of it. A fault beyond the range, or
// far outside it, is measured by a pass with it in the model instead (the
// analysis's ConfirmFaultsOutsideTheLinearRange), whose mechanisation it corrects.
#pragma once

#include <string>

namespace insdiag::engine {

enum class LinearRange {
  kWithin,
  kBeyond,      // the linearisation limits the estimate more than its noise
  kFarOutside,  // the estimate is an artefact of the linear model
};

// `relative_std_error`: SE/|β̂|.
LinearRange LinearRangeOf(double peak_attitude_error_rad, double relative_std_error);

// √(SE² + (ψ/2 · β̂)²): the estimate's standard error with the first-order
// model's error counted beside its noise SE.
double StandardErrorWithLinearisation(double estimate, double std_error,
                                      double peak_attitude_error_rad);

// What a candidate's note says for `range` (empty within it).
std::string LinearRangeNote(LinearRange range, double peak_attitude_error_rad,
                            double relative_std_error);

}  // namespace insdiag::engine
