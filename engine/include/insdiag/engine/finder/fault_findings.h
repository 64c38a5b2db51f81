// Faults in a report: the onset scan's candidates (finder/onset_scan.h) and
// the fault effects a model holds, turned into what the report says of the
// unit — candidates ranked with the other missing effects, the FAULTY
// verdict, a fault interval from the onset, and the sensor localised.
#pragma once

#include <optional>
#include <vector>

#include "insdiag/engine/finder/onset_scan.h"
#include "insdiag/engine/report.h"

namespace insdiag::engine {

// The scan's fits as missing-effect candidates (source "GLR"). Their
// likelihood ratio has two parameters, the magnitude and the onset: an added
// fault changes AIC by −T + 4 and BIC by −T + 2 ln N.
// A step and a ramp of one sensor axis within 2 of 2Δℓ name each other as
// look-alikes (correlated_with).
std::vector<EffectCandidate> FaultCandidates(const std::vector<OnsetFit>& fits, int scalar_updates);

// A fault the report must show.
struct FaultFinding {
  EffectTerm term;
  double onset_s = 0.0;
  double statistic = 0.0;  // T, or (β̂/SE)² for a fault effect in the model
  double p_value = 1.0;    // family-wise
  double estimate = 0.0;
  double std_error = 0.0;
};

// The significant fault candidates (Holm p below `alpha`) that explain the
// run better than any significant candidate of another kind (lower predicted
// ΔBIC): a step that only stands in for a missing constant effect — a scale
// factor's error appearing when the table starts to turn — is not a fault.
// One per sensor axis, the lowest ΔBIC: a step and a ramp on one axis are
// two explanations of one failure.
std::vector<FaultFinding> SignificantFaults(const std::vector<EffectCandidate>& candidates, double alpha);

// The model's fault effect `term` estimated at β̂ ± SE from `onset_s`: a
// finding when |β̂|/SE passes the two-sided normal test at `alpha`.
std::optional<FaultFinding> FaultInModel(const EffectTerm& term, double onset_s, double estimate, double std_error,
                                         double alpha);

// The findings in the report: verdict FAULTY, a fault interval on the
// sensor's raw channel from the onset to the run's end (ABRUPT for a step,
// GRADUAL for a ramp), and the sensor localised (method "GLR").
void ReportFaults(const std::vector<FaultFinding>& findings, double run_end_s, AnalysisReport& report);

}  // namespace insdiag::engine
