#include <algorithm>
#include <limits>
#include <optional>

#include "insdiag/engine/ident/drift_likelihood.h"

namespace insdiag::engine::ident {

absl::StatusOr<DriftLikelihoodResult> IdentifyDriftsFromStarts(const EpochRun& run, const ErrorModel& model,
                                                               const ErrorModel& a_priori,
                                                               const DriftSelection& which,
                                                               std::span<const double> tau_start_factors,
                                                               const DriftLikelihoodOptions& options) {
  std::vector<double> factors = {1.0};
  factors.insert(factors.end(), tau_start_factors.begin(), tau_start_factors.end());
  const double shortest_tau_s = 2.0 * run.update_interval_s;
  const double longest_tau_s = std::max(run.duration_s, shortest_tau_s);
  std::vector<DriftLikelihoodResult> fits;
  std::optional<double> before;  // the likelihood of the model as given: the first start's
  int iterations = 0, passes = 0;
  for (double factor : factors) {
    ErrorModel start = model;
    for (int d = 0; d < static_cast<int>(which.size()); ++d) {
      if (!which[static_cast<size_t>(d)]) continue;
      GaussMarkov& drift = DriftOf(start, d);
      drift.tau_s = std::clamp(drift.tau_s * factor, shortest_tau_s, longest_tau_s);
    }
    auto fit = IdentifyDriftsByLikelihood(run, start, a_priori, which, which, options);
    if (!fit.ok()) continue;
    if (!before.has_value() && factor == 1.0) before = fit->log_likelihood_before;
    iterations += fit->iterations;
    passes += fit->filter_passes;
    fits.push_back(*std::move(fit));
  }
  if (fits.empty()) return absl::FailedPreconditionError("no start of the drift identification converged");
  auto best = std::max_element(fits.begin(), fits.end(), [](const auto& a, const auto& b) {
    return a.log_likelihood_after < b.log_likelihood_after;
  });
  // Axis by axis, another start's drift where it raises the likelihood: the
  // starts climb one ridge per axis, and the best joint fit may hold an axis
  // on its worse side.
  ErrorModel combined = best->model;
  auto likelihood = [&](const ErrorModel& m) -> double {
    auto pass = RunForwardFilter(run, m);
    ++passes;
    return pass.ok() ? pass->log_likelihood : -std::numeric_limits<double>::infinity();
  };
  double combined_ll = likelihood(combined);
  bool changed = false;
  for (int d = 0; d < static_cast<int>(which.size()); ++d) {
    if (!which[static_cast<size_t>(d)]) continue;
    for (const DriftLikelihoodResult& other : fits) {
      if (&other == &*best || DriftOf(other.model, d) == DriftOf(combined, d)) continue;
      ErrorModel trial = combined;
      DriftOf(trial, d) = DriftOf(other.model, d);
      const double ll = likelihood(trial);
      if (ll > combined_ll) {
        combined = trial;
        combined_ll = ll;
        changed = true;
      }
    }
  }
  std::optional<DriftLikelihoodResult> result = *best;
  if (changed) {
    // EM from the combined drifts: its likelihood only rises from there.
    auto polished = IdentifyDriftsByLikelihood(run, combined, a_priori, which, which, options);
    if (polished.ok()) {
      iterations += polished->iterations;
      passes += polished->filter_passes;
      if (polished->log_likelihood_after > best->log_likelihood_after) result = *std::move(polished);
    }
  }
    // The improvement is measured from the model as given, not from a start.
  if (before.has_value()) result->log_likelihood_before = *before;
  result->iterations = iterations;
  result->filter_passes = passes;
  return *std::move(result);
}

absl::StatusOr<DriftLikelihoodResult> KeepDriftsWorthTheirParameters(const EpochRun& run, const ErrorModel& model,
                                                                     DriftLikelihoodResult fit, double log_n) {
  auto pass = RunForwardFilter(run, model);
  if (!pass.ok()) return pass.status();
  const double before = pass->log_likelihood;
  ErrorModel kept = model;
  std::vector<std::string> kept_names;
  for (int d = 0; d < 6; ++d) {
    if (DriftOf(fit.model, d) == DriftOf(model, d)) continue;
    const std::string name = DriftName(d);
    const int parameters = static_cast<int>(std::count_if(fit.identified.begin(), fit.identified.end(),
                                                          [&](const ParameterEstimate& p) {
                                                            return p.name.rfind(name + ".", 0) == 0;
                                                          }));
    ErrorModel alone = model;
    DriftOf(alone, d) = DriftOf(fit.model, d);
    auto trial = RunForwardFilter(run, alone);
    ++fit.filter_passes;
    if (!trial.ok() || !(2.0 * (trial->log_likelihood - before) > parameters * log_n)) continue;
    DriftOf(kept, d) = DriftOf(fit.model, d);
    kept_names.push_back(name + ".");
  }
  std::erase_if(fit.identified, [&](const ParameterEstimate& p) {
    return std::none_of(kept_names.begin(), kept_names.end(),
                        [&](const std::string& prefix) { return p.name.rfind(prefix, 0) == 0; });
  });
  auto after = RunForwardFilter(run, kept);
  if (!after.ok()) return after.status();
  ++fit.filter_passes;
  fit.model = kept;
  fit.log_likelihood_before = before;
  fit.log_likelihood_after = after->log_likelihood;
  return fit;
}

}  // namespace insdiag::engine::ident
