#include "analysis/fault_passes.h"

#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "analysis/model_pass.h"
#include "insdiag/engine/filter/linear_range.h"
#include "insdiag/engine/numerics/parallel_map.h"

namespace insdiag::engine::pipeline {
namespace {

// What a pass with one fault in the model measures of it.
struct FaultInAPass {
  double log_likelihood = 0.0;  // the profile likelihood (model_pass.h)
  double estimate = 0.0;        // the filter's final estimate of the fault, and its SE
  double std_error = 0.0;
};

absl::StatusOr<FaultInAPass> PassWithTheFault(const BenchRun& run, const ErrorModel& model,
                                              const OnsetFit& fit, const AnalysisOptions& options) {
  ErrorModel with_fault = model;
  with_fault.effects.push_back(
      FaultEffectAt(fit.term, fit.onset_s, fit.estimate, fit.std_error, options));
  // The fault's own pilot keeps the mechanisation within the linear range.
  auto forward = RunForwardFilter(run, with_fault, options.filter);
  if (!forward.ok()) return forward.status();
  if (forward->epochs() == 0) return absl::FailedPreconditionError("the run has no update epochs");
  const StateLayout layout(with_fault);
  const int state = layout.EffectOffset(static_cast<int>(with_fault.effects.size()) - 1);
  Eigen::MatrixXd P;
  UnpackSymmetric(forward->P_filt.row(forward->epochs() - 1).data(), forward->state_size, P);
  return FaultInAPass{ProfileLogLikelihood(*forward, with_fault),
                      forward->x_filt(forward->epochs() - 1, state), std::sqrt(P(state, state))};
}

// The scan's fit of fault candidate `c`, where it is one whose noise alone
// makes it a finding but whose first-order estimate lies beyond the linear
// range, or far outside it (linear_range.h): only a pass with it in the
// model measures it. Far outside, the first-order estimate is an artefact
// and the candidate was set aside as not identifiable; with the fault in its
// pilot the pass's mechanisation follows it, and its likelihood says whether
// the fault or a larger error elsewhere explains the innovations.
struct OutsideTheRange {
  const OnsetFit* fit = nullptr;
  LinearRange range = LinearRange::kWithin;
  double relative_std_error = 0.0;  // the scan's SE over its estimate
};

OutsideTheRange OutsideTheLinearRange(const EffectCandidate& c, const std::vector<OnsetFit>& fits,
                                      double alpha) {
  if (c.source != "GLR") return {};
  const auto fit =
      std::ranges::find_if(fits, [&](const OnsetFit& f) { return f.term.Name() == c.name; });
  if (fit == fits.end() || !fit->identifiable || !(fit->p_value < alpha) || fit->estimate == 0.0)
    return {};
  const double relative_std_error = fit->std_error / std::abs(fit->estimate);
  const LinearRange range = LinearRangeOf(fit->peak_attitude_error_rad, relative_std_error);
  if (range == LinearRange::kWithin) return {};
  return {&*fit, range, relative_std_error};
}

// `model` with fault `f` at its onset, its prior wide against its estimate.
void AddFault(const FaultFinding& f, const AnalysisOptions& options, ErrorModel& model) {
  model.effects.push_back(FaultEffectAt(f.term, f.onset_s, f.estimate, f.std_error, options));
}

// The p-value of `f`'s onset scan on `model` (its term absent from it), by
// Bonferroni over the `fault_terms` the first scan tried; `model` corrects
// the mechanisation, as for a fault beyond the linear range.
absl::StatusOr<double> FaultPValueBeside(const RunContext& c, const ErrorModel& model,
                                         const FaultFinding& f, int fault_terms) {
  auto epochs = CondenseRun(c.run, model, c.options.filter.update_interval_s);
  if (!epochs.ok()) return epochs.status();
  auto forward = RunForwardFilter(*epochs, model);
  if (!forward.ok()) return forward.status();
  const std::vector<OnsetFit> fits =
      ScanOnsets(*forward, StateLayout(model), *epochs, {f.term}, c.options.onset_scan);
  if (fits.empty() || !fits.front().identifiable) return 1.0;
  return std::min(1.0, fits.front().p_value * static_cast<double>(std::max(1, fault_terms)));
}

}  // namespace

// Faults beyond the scan's linear range or far outside it, measured by a pass
// with each in the model at the scan's onset (header).
void ConfirmFaultsOutsideTheLinearRange(const BenchRun& run, const ModelPass& a,
                                        const AnalysisOptions& options,
                                        std::vector<EffectCandidate>& faults) {
  const double alpha = options.finder.family_wise_alpha;
  std::vector<std::pair<EffectCandidate*, OutsideTheRange>> outside;
  for (EffectCandidate& c : faults) {
    if (const OutsideTheRange o = OutsideTheLinearRange(c, a.onsets, alpha); o.fit != nullptr) {
      outside.emplace_back(&c, o);
    }
  }
  // Each fault's pass is independent of the others'.
  const std::vector<absl::StatusOr<FaultInAPass>> passes =
      numerics::ParallelMap(outside.size(), [&](std::size_t i) {
        return PassWithTheFault(run, a.model, *outside[i].second.fit, options);
      });
  const double log_n = std::log(static_cast<double>(std::max(1, a.forward.scalar_updates)));
  for (std::size_t i = 0; i < outside.size(); ++i) {
    EffectCandidate& c = *outside[i].first;
    const OnsetFit& fit = *outside[i].second.fit;
    const LinearRange range = outside[i].second.range;
    const double relative_std_error = outside[i].second.relative_std_error;
    if (!passes[i].ok()) {
      absl::StrAppend(&c.note,
                      "; a pass with it in the model failed: ", passes[i].status().message());
      continue;
    }
    const FaultInAPass& measured = *passes[i];
    const double statistic = std::max(0.0, 2.0 * (measured.log_likelihood - a.log_likelihood));
    // The linear-range note gives way to what the pass measured.
    const std::string range_note =
        LinearRangeNote(range, fit.peak_attitude_error_rad, relative_std_error) + "; ";
    if (c.note.starts_with(range_note)) c.note.erase(0, range_note.size());
    c.note = absl::StrCat(
        absl::StrFormat("measured by a pass with it in the model at %.0f s: 2Δℓ %.1f against "
                        "the model without it (the scan's first-order estimate %.3g ± %.2g would "
                        "have put the filter %.2g rad off in attitude, %s its linear range); ",
                        fit.onset_s, statistic, fit.estimate, fit.std_error,
                        fit.peak_attitude_error_rad,
                        range == LinearRange::kFarOutside ? "far outside" : "beyond"),
        c.note);
    c.identifiable = true;
    if (c.size_in_drift_sigma.has_value()) {
      *c.size_in_drift_sigma *= std::abs(measured.estimate) / std::abs(fit.estimate);
    }
    c.statistic = statistic;
    c.p_value = OnsetPValue(c.statistic, fit.path_length);
    c.estimate = measured.estimate;
    c.std_error = measured.std_error;
    c.predicted_delta_aic = -c.statistic + 2.0 * c.dof;
    c.predicted_delta_bic = -c.statistic + c.dof * log_n;
  }
}

// Further faults re-tested beside the ones that stand (header).
std::vector<FaultFinding> FaultsThatStandTogether(const RunContext& c, const ModelPass& pass,
                                                  std::vector<FaultFinding> findings,
                                                  DecisionLog& decisions) {
  if (findings.size() < 2) return findings;
  const double alpha = c.options.finder.family_wise_alpha;
  const int fault_terms = static_cast<int>(pass.onsets.size());
  std::vector<FaultFinding> standing = {findings.front()};
  ErrorModel model = pass.model;
  AddFault(findings.front(), c.options, model);
  for (size_t k = 1; k < findings.size(); ++k) {
    const FaultFinding& f = findings[k];
    if (f.method == "GLR") {
      const absl::StatusOr<double> p = FaultPValueBeside(c, model, f, fault_terms);
      std::string before;
      for (const FaultFinding& s : standing)
        absl::StrAppend(&before, before.empty() ? "" : ", ", s.term.Name());
      if (!p.ok()) {
        decisions.Note(
            absl::StrFormat("%s at %.0f s could not be tested beside %s (%s): it stands",
                            f.term.Name(), f.onset_s, before, p.status().message()));
      } else if (!(*p < alpha)) {
        decisions.Note(absl::StrFormat(
            "%s at %.0f s is not a further fault: with %s in the model its onset scan gives p %.2g "
            "(over the %d fault terms), above %.2g: it stood for what the missing %s left in the "
            "innovations",
            f.term.Name(), f.onset_s, before, *p, fault_terms, alpha, before));
        continue;
      }
    }
    standing.push_back(f);
    AddFault(f, c.options, model);
  }
  return standing;
}

}  // namespace insdiag::engine::pipeline
