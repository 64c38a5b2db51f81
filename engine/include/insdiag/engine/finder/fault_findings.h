// Faults in a report: the onset scan's candidates (finder/onset_scan.h) and
// the fault effects a model holds, turned into what the report says of the
// unit — candidates ranked with the other missing effects, the FAULTY
// verdict, a fault interval from the onset, and the sensor localised.
#pragma once

#include <array>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "insdiag/engine/finder/onset_scan.h"
#include "insdiag/engine/finder/raw_sample_evidence.h"
#include "insdiag/engine/report.h"

namespace insdiag::engine {

// The scan's fits as missing-effect candidates (source "GLR"). Their
// likelihood ratio has two parameters, the magnitude and the onset: an added
// fault changes AIC by −T + 4 and BIC by −T + 2 ln N.
// A step and a ramp of one sensor axis within 2 of 2Δℓ name each other as
// look-alikes (correlated_with).
// `drift_sigma` (per sensor axis, gyros then accelerometers, in the family's
// unit) and `run_end_s`, where given, set each fault's size_in_drift_sigma.
// The drifts' τ and the white noise's density set the standard error of a
// ramp the raw samples show (AddRawSampleFaultCandidates).
struct FaultScale {
  std::array<double, kSensorAxisCount> drift_sigma{};
  std::array<double, kSensorAxisCount> drift_tau_s{};
  std::array<double, kSensorAxisCount> white_noise_density{};  // [unit·√s]
  double run_end_s = 0.0;
};

// Two faults whose 2Δℓ (equal parameter counts) or predicted ΔBIC are within
// this of each other are not worth telling apart (Kass & Raftery, JASA
// 90(430), 1995).
inline constexpr double kIndistinguishableDeltaBic = 2.0;

// The change of `raw_changes` that shows the fault `f` in the raw samples:
// of its sensor axis and shape, of its sign, and within 3 onset standard
// deviations plus the change's own tolerance of its onset; nullptr if none.
const RawSampleChange* SeenInRawSamples(const OnsetFit& f,
                                        std::span<const RawSampleChange> raw_changes);

// Whether two fits name each other as explanations of one signature: a step
// and a ramp of one sensor axis, or a fault the scan found nearly parallel to
// the other from its onset (OnsetFit::ambiguous_with).
bool AreLookAlikes(const OnsetFit& a, const OnsetFit& b);

// A fault candidate is seen in the raw samples (EffectCandidate::
// seen_in_raw_samples) when SeenInRawSamples finds its change.
std::vector<EffectCandidate> FaultCandidates(const std::vector<OnsetFit>& fits, int scalar_updates,
                                             const std::optional<FaultScale>& scale = std::nullopt,
                                             std::span<const RawSampleChange> raw_changes = {});

// The jumps and ramps the still segments' raw samples show, as fault
// candidates of source "RAW", each in place of its term's scan candidate
// unless that one is the stronger evidence (the smaller p-value) or places
// the samples' change (seen_in_raw_samples) with a p-value below
// `family_wise_alpha`: the scan's fit, over the whole run, places the onset
// better. The samples measure the sensor with no navigation model, so their
// onset and size stand (a z gyro's jump on a still table, which the
// navigation errors show through the heading alone):
//   - p-value: the channel's jump or ramp test (ident/allan.h: Jumps, Ramps)
//     times the six channels tested (Bonferroni), before the list's Holm
//     correction;
//   - a jump's estimate: the difference of the window means either side,
//     with the samples' own scatter of that difference away from it as its
//     standard error (RawSampleChange::std_error);
//   - a ramp's estimate: the samples' least-squares slope c over the L seconds after
//     the onset, with the slope's standard error under the axis' white noise
//     N and its drift taken as the walk it is over times short beside τ,
//     K = σ √(2/τ) (longer spans wander less: the error is an upper bound):
//       SE² = 12 N² / L³ + 6 K² / (5 L)
//     (the least-squares slope's variance over [0, L] for white noise, and
//     for a Wiener process ∫∫ f(s) f(t) min(s, t) / (∫ f²)² with f = t − L/2);
//   - statistic: what the navigation errors say of the same fault at that
//     onset, T = 2Δℓ of its magnitude (StatisticWithOnsetAt), and the predicted
//     ΔBIC −T + ln N of adding it there, which ranks it among the others;
//   - the look-alikes its term's scan named.
void AddRawSampleFaultCandidates(std::vector<EffectCandidate>& candidates,
                                 const std::vector<OnsetFit>& fits,
                                 std::span<const RawSampleChange> raw_changes, const EpochRun& run,
                                 int scalar_updates, const FaultScale& scale,
                                 double family_wise_alpha);

// Whether a candidate of `source` (EffectCandidate::source) is a fault at an
// onset: from the onset scan ("GLR") or the raw samples ("RAW").
bool IsFaultSource(std::string_view source);
bool IsFaultCandidate(const EffectCandidate& c);

// Whether `b` should come before `a`: both significant faults at `alpha`,
// named look-alikes of each other, their predicted ΔBIC within 2 (Kass &
// Raftery, JASA 90(430), 1995: the run cannot tell them apart through the
// navigation errors), and
//   - `b` seen in its sensor's raw samples and `a` not: the samples of a
//     still segment hold the sensor's own change, which needs no navigation
//     model (a y accelerometer's ramp and the x gyro step that tilts the
//     unit alike are told apart by the accelerometer's samples); or
//   - both alike in that, and `b` the smaller change of the unit in its
//     sensor's drift σ. On a still table a navigation-grade gyro's ramp of
//     24 σ and the z step of 440 σ that Earth rate makes look like it
//     explain the run equally; the smaller is the likelier failure.
bool IsLikelierLookAlike(const EffectCandidate& a, const EffectCandidate& b, double alpha);

// Moves each candidate of `ranked` ahead of the look-alikes it is likelier
// than (IsLikelierLookAlike), keeping the order otherwise.
void PutLikelierLookAlikesFirst(std::vector<EffectCandidate>& ranked, double alpha);

// A fault the report must show.
struct FaultFinding {
  EffectTerm term;
  double onset_s = 0.0;
  double statistic = 0.0;  // T, or (β̂/SE)² for a fault effect in the model
  double p_value = 1.0;    // family-wise
  double estimate = 0.0;
  double std_error = 0.0;
  std::string method = "GLR";  // the candidate's source: "GLR" or "RAW"
};

// The significant fault candidates (Holm p below `alpha`) that explain the
// run better than any significant candidate of another kind (lower predicted
// ΔBIC): a step that only stands in for a missing constant effect — a scale
// factor's error appearing when the table starts to turn — is not a fault.
// One per sensor axis, the lowest ΔBIC: a step and a ramp on one axis are
// two explanations of one failure, and so are faults named look-alikes of
// each other; of those within 2 of ΔBIC the likeliest (IsLikelierLookAlike).
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
