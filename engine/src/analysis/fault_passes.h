// The faults a scanned pass shows, measured by passes with them in the model
// rather than by the scan's first-order model alone: a fault beyond the
// scan's linear range, and a further fault beside the first. Each such pass
// condenses the run again with the faults in its pilot, whose feedback keeps
// the mechanisation within the first-order model's range
// (filter/epoch_run.h, filter/linear_range.h).
#pragma once

#include <string>
#include <vector>

#include "analysis/model_pass.h"
#include "analysis/run_context.h"
#include "insdiag/engine/decision.h"
#include "insdiag/engine/finder/fault_findings.h"

namespace insdiag::engine::pipeline {

// A fault the onset scan found beyond its linear range, or far outside it
// (linear_range.h), whose noise alone would make it a finding: the scan's
// first-order estimate cannot measure it, but the filter with the fault in
// its pilot can. Far outside, the candidate was not identifiable; measured,
// it is.
// Each such candidate of `faults` takes what a pass of `a`'s model plus the
// fault at the scan's onset measures against `a`: the fitted 2Δℓ as its
// statistic, Davies' bound over the onsets as the scan's, and the pass's
// estimate and SE. One condensation and forward pass per such fault, in parallel.
void ConfirmFaultsOutsideTheLinearRange(const BenchRun& run, const ModelPass& a,
                                        const AnalysisOptions& options,
                                        std::vector<EffectCandidate>& faults);

// The scan's significant faults (SignificantFaults, most significant first)
// that stand together: each further fault of the navigation errors is
// scanned again with the faults before it that stand in the model, and is
// kept where its onset scan there (Bonferroni over the fault terms the first
// scan tried) is still below the family-wise level. A fault that only took
// up what an earlier one leaves in the innovations (a y gyro ramp beside the
// x accelerometer ramp whose tilt it mimics) is not a second failure; a note
// for `notes` says so. A fault of the raw samples (source RAW) is their
// evidence, not the innovations', and stands as it is.
std::vector<FaultFinding> FaultsThatStandTogether(const RunContext& c, const ModelPass& pass,
                                                  std::vector<FaultFinding> findings,
                                                  DecisionLog& decisions);

}  // namespace insdiag::engine::pipeline
