#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "ident/drift_em.h"
#include "insdiag/engine/ident/drift_likelihood.h"
#include "insdiag/engine/numerics/parallel_map.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine::ident {
namespace {

// ℓ of `model` on `run` by one filter pass, counted into `passes`.
absl::StatusOr<double> LogLikelihoodOf(const EpochRun& run, const ErrorModel& model, int& passes) {
  auto pass = RunForwardFilter(run, model);
  ++passes;
  if (!pass.ok()) return pass.status();
  return pass->log_likelihood;
}

// ℓ for comparing candidates: a model the filter cannot run is never the better.
double LogLikelihoodOrWorst(const EpochRun& run, const ErrorModel& model, int& passes) {
  return LogLikelihoodOf(run, model, passes).value_or(-std::numeric_limits<double>::infinity());
}

// The correlation times a search tries: from two update intervals to the run's length.
struct TauRange {
  double shortest_s = 0.0, longest_s = 0.0;
  explicit TauRange(const EpochRun& run)
      : shortest_s(2.0 * run.update_interval_s), longest_s(std::max(run.duration_s, shortest_s)) {}
};

struct GridPoint {
  ErrorModel model;
  double model_log_likelihood = 0.0;  // ℓ of the model the grid started from
};

// The best point of the coarse grid of DriftStartOptions, one drift at a
// time in turn, each searched with the drifts before it at their best
// (coordinate ascent: one drift's misfit swamps another's likelihood until
// it is fitted): σ for the drifts of `which`, and τ too for those of
// `tau_too` (the others keep the model's τ). The grid includes the model's
// own point for a σ-only drift, and the result is never below the model's
// likelihood. Points the raw samples refuse (`ceilings`) are not tried.
// Counts its passes into `passes`.
GridPoint GridStart(const EpochRun& run, const ErrorModel& model, const DriftSelection& which,
                    const DriftSelection& tau_too, const DriftStartOptions& starts,
                    const DriftCeilings& ceilings, int& passes) {
  const TauRange range(run);
  GridPoint out{model, LogLikelihoodOrWorst(run, model, passes)};
  double best_ll = out.model_log_likelihood;
  const int points = std::max(1, starts.grid_tau_points);
  for (const DriftAxis d : DriftAxis::All()) {
    if (!which.Contains(d) || !(DriftOf(model, d).sigma > 0.0)) continue;
    const GaussMarkov specified = DriftOf(model, d);
    const bool with_tau = tau_too.Contains(d);
    std::vector<GaussMarkov> trials;
    for (int t = 0; t < (with_tau ? points : 1); ++t) {
      const double fraction = points > 1 ? static_cast<double>(t) / (points - 1) : 0.5;
      const double tau_s =
          with_tau ? range.shortest_s * std::pow(range.longest_s / range.shortest_s, fraction) : specified.tau_s;
      for (double factor : starts.grid_sigma_factors) {
        if (!with_tau && factor == 1.0) continue;  // the model's own point, already weighed
        const GaussMarkov trial{specified.sigma * factor, tau_s};
        if (ceilings.Allows(d, trial)) trials.push_back(trial);
      }
    }
    // The grid's points are independent passes; the best is taken in grid order.
    const std::vector<double> ll = numerics::ParallelMap(trials.size(), [&](std::size_t i) {
      ErrorModel trial = out.model;
      DriftOf(trial, d) = trials[i];
      int unused_passes = 0;
      return LogLikelihoodOrWorst(run, trial, unused_passes);
    });
    passes += static_cast<int>(trials.size());
    GaussMarkov chosen = DriftOf(out.model, d);
    for (std::size_t i = 0; i < trials.size(); ++i) {
      if (ll[i] > best_ll) {
        best_ll = ll[i];
        chosen = trials[i];
      }
    }
    DriftOf(out.model, d) = chosen;
  }
  return out;
}

}  // namespace

absl::StatusOr<DriftLikelihoodResult> IdentifyDriftsFromStarts(const EpochRun& run, const ErrorModel& model,
                                                               const ErrorModel& a_priori,
                                                               const DriftSelection& which,
                                                               const DriftStartOptions& starts,
                                                               const DriftCeilings& ceilings,
                                                               const DriftLikelihoodOptions& options) {
  const TauRange range(run);
  int iterations = 0, passes = 0;
  std::vector<ErrorModel> start_models = {model};
  for (double factor : starts.tau_factors) {
    ErrorModel start = model;
    for (const DriftAxis d : DriftAxis::All()) {
      if (!which.Contains(d)) continue;
      GaussMarkov& drift = DriftOf(start, d);
      drift.tau_s = std::clamp(drift.tau_s * factor, range.shortest_s, range.longest_s);
    }
    start_models.push_back(std::move(start));
  }
  if (starts.raw_sample_drifts.has_value()) {
    ErrorModel start = model;
    for (const DriftAxis d : DriftAxis::All()) {
      const GaussMarkov& suggested =
          (*starts.raw_sample_drifts)[static_cast<std::size_t>(d.Index())];
      if (!which.Contains(d) || !(suggested.sigma > 0.0) || !(DriftOf(model, d).sigma > 0.0))
        continue;
      DriftOf(start, d) = {suggested.sigma,
                           std::clamp(suggested.tau_s, range.shortest_s, range.longest_s)};
    }
    start_models.push_back(std::move(start));
  }
  if (starts.grid_tau_points > 0)
    start_models.push_back(
        GridStart(run, model, which, which, starts, ceilings, passes).model);
  // EM from each start: independent runs, taken in the starts' order. The
  // fits are compared on their maxima; only the one kept gets its errors.
  std::vector<absl::StatusOr<drift_em::FitWithoutErrors>> from_starts =
      numerics::ParallelMap(start_models.size(), [&](std::size_t i) {
        return drift_em::FitDriftsWithinCeilings(run, start_models[i], a_priori, which, which, ceilings, options);
      });
  std::vector<drift_em::FitWithoutErrors> fits;
  std::optional<double> before;  // the likelihood of the model as given: the first start's
  for (size_t i = 0; i < start_models.size(); ++i) {
    auto& fit = from_starts[i];
    if (!fit.ok()) continue;
    if (i == 0) before = fit->result.log_likelihood_before;
    iterations += fit->result.iterations;
    passes += fit->result.filter_passes;
    fits.push_back(*std::move(fit));
  }
  if (fits.empty()) return absl::FailedPreconditionError("no start of the drift identification converged");
  auto best = std::max_element(fits.begin(), fits.end(), [](const auto& a, const auto& b) {
    return a.result.log_likelihood_after < b.result.log_likelihood_after;
  });
  // Axis by axis, another start's drift where it raises the likelihood: the
  // starts climb one ridge per axis, and the best joint fit may hold an axis
  // on its worse side.
  ErrorModel combined = best->result.model;
  double combined_ll = best->result.log_likelihood_after;
  bool changed = false;
  for (const DriftAxis d : DriftAxis::All()) {
    if (!which.Contains(d)) continue;
    for (const drift_em::FitWithoutErrors& fitted : fits) {
      const DriftLikelihoodResult& other = fitted.result;
      if (&fitted == &*best || DriftOf(other.model, d) == DriftOf(combined, d)) continue;
      ErrorModel trial = combined;
      DriftOf(trial, d) = DriftOf(other.model, d);
      const double ll = LogLikelihoodOrWorst(run, trial, passes);
      if (ll > combined_ll) {
        combined = trial;
        combined_ll = ll;
        changed = true;
      }
    }
  }
  drift_em::FitWithoutErrors kept = *std::move(best);
  if (changed) {
    // EM from the combined drifts: its likelihood only rises from there.
    auto polished = drift_em::FitDriftsWithinCeilings(run, combined, a_priori, which, which, ceilings, options);
    if (polished.ok()) {
      iterations += polished->result.iterations;
      passes += polished->result.filter_passes;
      if (polished->result.log_likelihood_after > kept.result.log_likelihood_after) kept = *std::move(polished);
    }
  }
  const int passes_before_errors = kept.result.filter_passes;
  auto result = drift_em::WithErrors(run, std::move(kept), a_priori, options);
  if (!result.ok()) return result.status();
  // The improvement is measured from the model as given, not from a start.
  if (before.has_value()) result->log_likelihood_before = *before;
  result->iterations = iterations;
  result->filter_passes = passes + result->filter_passes - passes_before_errors;
  return result;
}

absl::StatusOr<DriftLikelihoodResult> IdentifyDriftsFromGrid(const EpochRun& run, const ErrorModel& model,
                                                             const ErrorModel& a_priori, const DriftSelection& which,
                                                             const DriftSelection& tau_too,
                                                             const DriftStartOptions& starts,
                                                             const DriftCeilings& ceilings,
                                                             const DriftLikelihoodOptions& options) {
  if (!which.Any()) {
    return IdentifyDriftsByLikelihood(run, model, a_priori, which, tau_too, ceilings, options);
  }
  int passes = 0;
  const GridPoint start =
      GridStart(run, model, which, tau_too, starts, ceilings, passes);
  auto fit = IdentifyDriftsByLikelihood(run, start.model, a_priori, which, tau_too, ceilings, options);
  if (!fit.ok()) return fit.status();
  // The improvement is measured from the model as given, not from the grid's point.
  fit->log_likelihood_before = start.model_log_likelihood;
  fit->filter_passes += passes;
  return fit;
}

absl::StatusOr<std::vector<std::string>> WidenErrorsToTheLikelihoodRatio(const EpochRun& run,
                                                                         const ErrorModel& reference,
                                                                         DriftLikelihoodResult& fit) {
  std::vector<std::string> widened;
  if (fit.identified.empty()) return widened;
  const double at_fit = fit.log_likelihood_after;
  const auto departs = [&](DriftAxis d) {
    const GaussMarkov& before = DriftOf(reference, d);
    return DriftOf(fit.model, d) != before && before.sigma > 0.0 && before.tau_s > 0.0;
  };
  // ℓ with each departing drift back at its reference: independent passes.
  const auto at_references = numerics::ParallelMap(DriftAxis::kCount, [&](std::size_t i) -> absl::StatusOr<double> {
    const DriftAxis d = DriftAxis::FromIndex(static_cast<int>(i));
    if (!departs(d)) return absl::CancelledError("at its reference");
    ErrorModel without = fit.model;
    DriftOf(without, d) = DriftOf(reference, d);
    int passes = 0;
    return LogLikelihoodOf(run, without, passes);
  });
  for (const DriftAxis d : DriftAxis::All()) {
    const GaussMarkov& before = DriftOf(reference, d);
    if (!departs(d)) continue;
    double wald = 0.0;
    std::vector<ParameterEstimate*> estimates;
    for (ParameterEstimate& p : fit.identified) {
      if (DriftOfParameter(p.name) != d || !(p.value > 0.0) || !(p.std_error > 0.0)) continue;
      const bool sigma = p.name == DriftSigmaName(d);
      const double reference_value = sigma ? before.sigma : before.tau_s;
      const double z = std::log(p.value / reference_value) / (p.std_error / p.value);
      wald += z * z;
      estimates.push_back(&p);
    }
    if (estimates.empty()) continue;
    ++fit.filter_passes;
    const auto& at_reference = at_references[static_cast<std::size_t>(d.Index())];
    if (!at_reference.ok()) continue;
    // The floor is χ²'s median: below it neither statistic says the estimate
    // departs from the reference, and a test-based SE would only measure how
    // near the two points are.
    const double floor = stats::ChiSquareQuantile(0.5, static_cast<double>(estimates.size()));
    const double statistic = std::max(2.0 * (at_fit - *at_reference), floor);
    if (!(wald > statistic)) continue;
    const double widen = std::sqrt(wald / statistic);
    for (ParameterEstimate* p : estimates) {
      const double log_se = widen * p->std_error / p->value;
      p->std_error = p->value * log_se;
      p->ci95_low = p->value * std::exp(-1.96 * log_se);
      p->ci95_high = p->value * std::exp(1.96 * log_se);
    }
    widened.push_back(DriftName(d));
  }
  return widened;
}

absl::StatusOr<DriftLikelihoodResult> KeepDriftsWorthTheirParameters(const EpochRun& run,
                                                                     const ErrorModel& model,
                                                                     DriftLikelihoodResult fit) {
  ++fit.filter_passes;
  const auto model_pass = RunForwardFilter(run, model);
  if (!model_pass.ok()) return model_pass.status();
  const double before = model_pass->log_likelihood;
  const double log_n = std::log(static_cast<double>(std::max(1, model_pass->scalar_updates)));
  ErrorModel kept = fit.model;
  double kept_ll = fit.log_likelihood_after;
  auto parameters_of = [&](DriftAxis d) {
    return static_cast<int>(
        std::count_if(fit.identified.begin(), fit.identified.end(),
                      [&](const ParameterEstimate& p) { return DriftOfParameter(p.name) == d; }));
  };
  for (;;) {
    // Each kept drift put back to the model's values: independent passes.
    const auto without_each = numerics::ParallelMap(DriftAxis::kCount, [&](std::size_t i) -> absl::StatusOr<double> {
      const DriftAxis d = DriftAxis::FromIndex(static_cast<int>(i));
      if (DriftOf(kept, d) == DriftOf(model, d)) return absl::CancelledError("not kept");
      ErrorModel without = kept;
      DriftOf(without, d) = DriftOf(model, d);
      int passes = 0;
      return LogLikelihoodOf(run, without, passes);
    });
    std::optional<DriftAxis> least;
    double least_margin = 0.0, least_ll = 0.0;
    for (const DriftAxis d : DriftAxis::All()) {
      if (DriftOf(kept, d) == DriftOf(model, d)) continue;
      ++fit.filter_passes;
      const auto& ll = without_each[static_cast<std::size_t>(d.Index())];
      // A drift the filter cannot run without is worth its parameters.
      if (!ll.ok()) continue;
      const double margin = 2.0 * (kept_ll - *ll) - parameters_of(d) * log_n;
      if (!least.has_value() || margin < least_margin) {
        least = d;
        least_margin = margin;
        least_ll = *ll;
      }
    }
    if (!least.has_value() || least_margin > 0.0) break;
    DriftOf(kept, *least) = DriftOf(model, *least);
    kept_ll = least_ll;
  }
  std::erase_if(fit.identified, [&](const ParameterEstimate& p) {
    for (const DriftAxis d : DriftAxis::All()) {
      if (DriftOf(kept, d) != DriftOf(model, d) && DriftOfParameter(p.name) == d) return false;
    }
    return true;
  });
  fit.model = kept;
  fit.log_likelihood_before = before;
  fit.log_likelihood_after = kept_ll;
  return fit;
}

}  // namespace insdiag::engine::ident
