#include "insdiag/engine/ident/drift_likelihood.h"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "ident/drift_em.h"
#include "insdiag/engine/model/parameter_field.h"
#include "insdiag/engine/numerics/parallel_map.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine::ident {

using namespace drift_em;  // the likelihood's EM, shared by the drifts' identification and the
                           // structure tests

double StructurePValue(double statistic, int dof, int starts) {
  return std::min(1.0, stats::ChiSquareSurvival(statistic, dof) * static_cast<double>(starts));
}

double NestedPValue(const StructureEstimate& s) { return StructurePValue(s.statistic, s.dof, s.starts); }

namespace {

// One EM fit of the selected drifts from `model`, without their errors.
absl::StatusOr<FitWithoutErrors> FitDriftsByEm(const EpochRun& run, const ErrorModel& model,
                                              const DriftSelection& which, const DriftSelection& tau_too,
                                              const DriftLikelihoodOptions& options) {
  FitWithoutErrors fit;
  fit.result.model = model;
  for (const DriftAxis d : DriftAxis::All()) {
    // A drift the model leaves out (σ = 0) has no state to identify.
    if (!which.Contains(d) || !HasDrift(model, d)) continue;
    fit.parameters.push_back({Kind::kSigma, d});
    if (tau_too.Contains(d)) fit.parameters.push_back({Kind::kTau, d});
  }
  if (fit.parameters.empty()) {
    fit.result.converged = true;
    return fit;
  }
  Maximiser em(run, model, fit.parameters, options, fit.result);
  auto theta = FitInto(em, fit.result, &fit.result.log_likelihood_before);
  if (!theta.ok()) return theta.status();
  fit.theta = *std::move(theta);
  return fit;
}

// The fit's drifts the ceilings refuse, each with the value it is held at.
std::vector<HeldDrift> RefutedByRawSamples(const DriftLikelihoodResult& fit,
                                           const ErrorModel& a_priori, const DriftSelection& which,
                                           const DriftCeilings& ceilings) {
  std::vector<HeldDrift> out;
  for (const DriftAxis d : DriftAxis::All()) {
    if (!which.Contains(d)) continue;
    const GaussMarkov& estimate = DriftOf(fit.model, d);
    const DriftCeilings::Excess excess = ceilings.ExcessOf(d, estimate);
    if (excess.ratio <= 1.0) continue;
    out.push_back({d, estimate, excess, ceilings.Within(d, DriftOf(a_priori, d))});
  }
  return out;
}

}  // namespace

namespace drift_em {

absl::StatusOr<FitWithoutErrors> FitDriftsWithinCeilings(const EpochRun& run, const ErrorModel& model,
                                                         const ErrorModel& a_priori, const DriftSelection& which,
                                                         const DriftSelection& tau_too,
                                                         const DriftCeilings& ceilings,
                                                         const DriftLikelihoodOptions& options) {
  if (auto st = ValidateOptions(options); !st.ok()) return st;
  auto fit = FitDriftsByEm(run, model, which, tau_too, options);
  if (!fit.ok()) return fit.status();
  DriftSelection selected = which;
  std::vector<HeldDrift> held;
  int iterations = fit->result.iterations, passes = fit->result.filter_passes;
  const double before = fit->result.log_likelihood_before;
  // Each round holds what the samples refute and fits the rest again; a
  // drift is held once, so at most one round per drift.
  for (auto refuted = RefutedByRawSamples(fit->result, a_priori, selected, ceilings);
       !refuted.empty();
       refuted = RefutedByRawSamples(fit->result, a_priori, selected, ceilings)) {
    ErrorModel start = fit->result.model;
    for (const HeldDrift& h : refuted) {
      DriftOf(start, h.drift) = h.held;
      selected.Set(h.drift, false);
      held.push_back(h);
    }
    fit = FitDriftsByEm(run, start, selected, tau_too, options);
    if (!fit.ok()) return fit.status();
    if (fit->result.filter_passes == 0) {
      // Nothing left to fit: the held model's likelihood still counts.
      ++fit->result.filter_passes;
      auto pass = RunForwardFilter(run, fit->result.model);
      if (!pass.ok()) return pass.status();
      fit->result.log_likelihood_after = pass->log_likelihood;
    }
    iterations += fit->result.iterations;
    passes += fit->result.filter_passes;
  }
  fit->start = model;
  fit->result.held_by_raw_samples = std::move(held);
  fit->result.log_likelihood_before = before;
  fit->result.iterations = iterations;
  fit->result.filter_passes = passes;
  return fit;
}

absl::StatusOr<DriftLikelihoodResult> WithErrors(const EpochRun& run, FitWithoutErrors fit,
                                                 const ErrorModel& a_priori,
                                                 const DriftLikelihoodOptions& options) {
  DriftLikelihoodResult& out = fit.result;
  if (fit.parameters.empty()) return std::move(out);
  const std::vector<Parameter>& parameters = fit.parameters;
  const Eigen::VectorXd& theta = fit.theta;
  const double l0 = out.log_likelihood_after;
  Maximiser em(run, out.model, parameters, options, out);
  // The curvature at the estimate (observed information) in ln σ, or in
  // (ln σ, ln τ) jointly where τ is identified too: the two trade along a
  // ridge, and their errors must show it. From the smoother's moments, every
  // parameter's in one set of passes, each drift's block read from it.
  const bool from_moments =
      options.information == DriftLikelihoodOptions::Information::kSmootherMoments;
  Eigen::MatrixXd all_information;
  if (from_moments) {
    std::vector<Eigen::Index> every(parameters.size());
    for (size_t j = 0; j < parameters.size(); ++j) every[j] = static_cast<Eigen::Index>(j);
    auto information = em.MomentInformation(theta, every);
    if (!information.ok()) return information.status();
    all_information = *std::move(information);
  }
  bool any_flat = false;
  for (size_t j = 0; j < parameters.size(); ++j) {
    const Parameter& p = parameters[j];
    if (p.kind != Kind::kSigma) continue;
    const auto i = static_cast<Eigen::Index>(j);
    const bool with_tau = j + 1 < parameters.size() && parameters[j + 1].kind == Kind::kTau;
    std::vector<double> log_se;
    double log_correlation = std::numeric_limits<double>::quiet_NaN();
    if (with_tau) {
      Eigen::MatrixXd information;
      if (from_moments) {
        information = all_information.block(i, i, 2, 2);
      } else {
        auto differences = em.BlockInformation(theta, {i, i + 1}, l0);
        if (!differences.ok()) return differences.status();
        information = *std::move(differences);
      }
      if (information(0, 0) > 0.0 && information.determinant() > 0.0) {
        const Eigen::MatrixXd covariance = information.inverse();
        log_se = {std::sqrt(covariance(0, 0)), std::sqrt(covariance(1, 1))};
        log_correlation = covariance(0, 1) / (log_se[0] * log_se[1]);
      }
    } else {
      double information = 0.0;
      if (from_moments) {
        information = all_information(i, i);
      } else {
        auto difference = em.Information(theta, i, l0);
        if (!difference.ok()) return difference.status();
        information = *difference;
      }
      if (information > 0.0) log_se = {1.0 / std::sqrt(information)};
    }
    const size_t count = with_tau ? 2 : 1;
    for (size_t k = 0; k < count; ++k) {
      const Parameter& q = parameters[j + k];
      if (log_se.empty()) {
        // The likelihood is flat here: the run's motion does not make the
        // drift observable (a level gyro's heading drift on a still table).
        // Not an estimate — the model keeps its value.
        ValueOf(out.model, q) = ValueOf(fit.start, q);
        out.not_identifiable.push_back(NameOf(q));
        any_flat = true;
        continue;
      }
      out.identified.push_back(EstimateOf(q, std::exp(theta[i + static_cast<Eigen::Index>(k)]), log_se[k], a_priori));
      if (with_tau) {
        out.identified.back().jointly_with = NameOf(parameters[j + 1 - k]);
        out.identified.back().log_correlation = log_correlation;
      }
    }
  }
  if (any_flat) {
    auto kept = em.LogLikelihood(out.model);
    if (!kept.ok()) return kept.status();
    out.log_likelihood_after = *kept;
  }
  return std::move(out);
}

}  // namespace drift_em

absl::StatusOr<DriftLikelihoodResult> IdentifyDriftsByLikelihood(
    const EpochRun& run, const ErrorModel& model, const ErrorModel& a_priori,
    const DriftSelection& which, const DriftSelection& tau_too, const DriftCeilings& ceilings,
    const DriftLikelihoodOptions& options) {
  auto fit = FitDriftsWithinCeilings(run, model, a_priori, which, tau_too, ceilings, options);
  if (!fit.ok()) return fit.status();
  return WithErrors(run, *std::move(fit), a_priori, options);
}

namespace {

// A structure kind the likelihood tests: its parameters after the axis'
// drift σ (the first is its magnitude) and its effect at a start.
struct StructureKind {
  bool second_order = false;
  std::string Name(DriftAxis drift) const { return second_order ? SecondOrderName(drift) : WalkName(drift); }
  std::vector<Kind> Kinds() const {
    if (second_order) return {Kind::kPairSigma, Kind::kPairDecayRate, Kind::kPairFrequency};
    return {Kind::kWalk};
  }
  // Starting points: one for a walk, one per starting period for a pair.
  size_t Starts(const DriftLikelihoodOptions& o) const {
    return second_order ? o.second_order_start_periods_s.size() : 1;
  }
  // The effect at start `start` for a drift of a-priori σ and τ `specified`
  // (header: a walk at the drift's short-term level σ√(2/τ); a pair of the
  // drift's σ, its decay time the starting period).
  absl::StatusOr<ModelEffect> At(DriftAxis drift, size_t start, const GaussMarkov& specified,
                                 const DriftLikelihoodOptions& o) const {
    auto terms = ParseEffectSelector(Name(drift));
    if (!terms.ok()) return terms.status();
    ModelEffect e;
    e.term = terms->front();
    if (second_order) {
      const double period_s = o.second_order_start_periods_s[start];
      e.second_order_sigma = specified.sigma;
      e.second_order_alpha_per_s = 1.0 / period_s;
      e.second_order_beta_rad_s = 2.0 * std::numbers::pi / period_s;
    } else {
      e.random_walk_density = specified.sigma * std::sqrt(2.0 / specified.tau_s);
    }
    return e;
  }
};

// The report's parameters of a fitted structure from its estimates in θ
// (value, SE of its log): a walk's K; a pair's σ₂, τ₂ = 1/α and period 2π/β
// (ln τ₂ = −ln α: the same SE in the log).
std::vector<ParameterEstimate> ReportedParameters(const StructureKind& kind, DriftAxis drift,
                                                  const std::vector<ParameterEstimate>& fitted) {
  if (!kind.second_order) return fitted;
  std::vector<ParameterEstimate> out{fitted[0]};
  for (size_t k = 1; k < 3; ++k) {
    ParameterEstimate e = fitted[k];
    const double log_se = e.std_error / e.value;
    const double scale = k == 1 ? 1.0 : 2.0 * std::numbers::pi;
    e.name = ParameterName(SecondOrderName(drift),
                           k == 1 ? ParameterField::kTau : ParameterField::kPeriod);
    e.value = scale / fitted[k].value;
    e.std_error = e.value * log_se;
    e.ci95_low = e.value * std::exp(-1.96 * log_se);
    e.ci95_high = e.value * std::exp(1.96 * log_se);
    e.unit = std::string("s");
    out.push_back(e);
  }
  return out;
}

// The drift a structure's start is scaled to: the a-priori model's where it
// has one, else the model's.
const GaussMarkov& SpecifiedDrift(const ErrorModel& model, const ErrorModel& a_priori,
                                  DriftAxis d) {
  return HasDrift(a_priori, d) ? DriftOf(a_priori, d) : DriftOf(model, d);
}

// The axes whose structure the screen keeps, each with its best start.
struct ScreenedStructures {
  std::vector<DriftAxis> kept_axes;
  std::array<size_t, DriftAxis::kCount> best_start{};  // by DriftAxis::Index
};

// The screen: from each start, every candidate at the structure hypothesis
// (the drift at its a-priori σ, not wider: a widened drift took the slow
// variance the structure would explain), one EM step; an axis keeps the
// start whose step lets the magnitude grow most. The starts' steps are
// independent passes: on every core, read in order.
absl::StatusOr<ScreenedStructures> ScreenStructureStarts(
    const EpochRun& run, const ErrorModel& model, const ErrorModel& a_priori,
    const std::vector<DriftAxis>& candidates, const StructureKind& kind,
    const DriftLikelihoodOptions& options, DriftLikelihoodResult& out) {
  const std::vector<Kind> kinds = kind.Kinds();
  const auto per_axis = static_cast<Eigen::Index>(kinds.size()) + 1;
  struct ScreenStep {
    Eigen::VectorXd theta;
    Maximiser::Step step;
    int filter_passes = 0;
  };
  auto screened = numerics::ParallelMap(kind.Starts(options), [&](std::size_t start) -> absl::StatusOr<ScreenStep> {
    ErrorModel trial = model;
    std::vector<Parameter> parameters;
    for (const DriftAxis d : candidates) {
      auto effect = kind.At(d, start, SpecifiedDrift(model, a_priori, d), options);
      if (!effect.ok()) return effect.status();
      GaussMarkov& drift = DriftOf(trial, d);
      drift.sigma = std::min(drift.sigma, SpecifiedDrift(model, a_priori, d).sigma);
      trial.effects.push_back(*effect);
      parameters.push_back({Kind::kSigma, d});
      for (Kind k : kinds) parameters.push_back({k, d});
    }
    DriftLikelihoodResult passes;
    Maximiser screen(run, trial, parameters, options, passes);
    ScreenStep out_step{screen.Start(), {}, 0};
    auto step = screen.EmStep(out_step.theta);
    if (!step.ok()) return step.status();
    out_step.step = *std::move(step);
    out_step.filter_passes = passes.filter_passes;
    return out_step;
  });
  ScreenedStructures result;
  std::array<double, DriftAxis::kCount> best_growth;
  best_growth.fill(0.0);
  for (size_t start = 0; start < screened.size(); ++start) {
    if (!screened[start].ok()) return screened[start].status();
    const ScreenStep& s_step = *screened[start];
    out.filter_passes += s_step.filter_passes;
    if (start == 0) out.log_likelihood_before = s_step.step.log_likelihood;
    for (size_t c = 0; c < candidates.size(); ++c) {
      const auto magnitude = static_cast<Eigen::Index>(c) * per_axis + 1;
      const double growth = s_step.step.next[magnitude] - s_step.theta[magnitude];
      const auto d = static_cast<size_t>(candidates[c].Index());
      if (growth > best_growth[d]) {
        best_growth[d] = growth;
        result.best_start[d] = start;
      }
    }
  }
  for (const DriftAxis d : candidates) {
    if (best_growth[static_cast<size_t>(d.Index())] > 0.0) result.kept_axes.push_back(d);
  }
  return result;
}

// How far a fitted structure, with its axis's drift, stands beyond what the
// raw samples allow; nothing when within. A walk's density is its drift's
// rate random walk, a pair's (σ₂, α, β) its own term (drift_ceiling.h); the
// effect holds zero for the other kind's.
std::optional<DriftCeilings::Excess> StructureRefused(const ErrorModel& fitted,
                                                      const StructureEstimate& structure,
                                                      const DriftCeilings& ceilings) {
  const ModelEffect& e = structure.fitted;
  AllanNoiseTerms terms;
  terms.markov_sigma = DriftOf(fitted, structure.drift).sigma;
  terms.markov_tau_s = DriftOf(fitted, structure.drift).tau_s;
  terms.rate_random_walk = e.random_walk_density;
  const DriftCeilings::Excess excess = ceilings.ExcessOf(
      structure.drift, terms,
      {e.second_order_sigma, e.second_order_alpha_per_s, e.second_order_beta_rad_s});
  if (excess.ratio <= 1.0) return std::nullopt;
  return excess;
}

// Each kept structure's nested test: ℓ̂₀ is the joint model's without it, its
// drift σ re-fitted alone. EM for σ alone starts from the model's σ, not the
// joint fit's: from a σ the structure has relieved, EM crawls up and would
// stop below ℓ̂₀ (its steps fall under the tolerance long before it gets
// there), which inflates the statistic. The fits are independent: on every
// core.
absl::StatusOr<std::vector<StructureEstimate>> TestEachWithoutIt(
    const EpochRun& run, const ErrorModel& model, const std::vector<DriftAxis>& kept_axes,
    const StructureKind& kind, const DriftLikelihoodOptions& options, DriftLikelihoodResult& out) {
  auto without_each = numerics::ParallelMap(kept_axes.size(), [&](std::size_t c) {
    const DriftAxis d = kept_axes[c];
    ErrorModel without = out.model;
    without.effects.erase(without.effects.begin() + EffectOf(without, kind.Name(d)));
    DriftOf(without, d).sigma = DriftOf(model, d).sigma;
    DriftLikelihoodResult alone_result;
    Maximiser alone(run, without, {Parameter{Kind::kSigma, d}}, options, alone_result);
    absl::Status fitted = FitInto(alone, alone_result, nullptr).status();
    return std::pair{fitted, alone_result};
  });
  std::vector<StructureEstimate> fits;
  for (size_t c = 0; c < kept_axes.size(); ++c) {
    const auto& [fitted_alone, alone_result] = without_each[c];
    if (!fitted_alone.ok()) return fitted_alone;
    const DriftAxis d = kept_axes[c];
    StructureEstimate w;
    w.drift = d;
    w.effect = kind.Name(d);
    w.dof = static_cast<int>(kind.Kinds().size());
    w.starts = static_cast<int>(kind.Starts(options));
    out.filter_passes += alone_result.filter_passes;
    w.log_likelihood_without = alone_result.log_likelihood_after;
    w.statistic = std::max(0.0, 2.0 * (out.log_likelihood_after - w.log_likelihood_without));
    fits.push_back(std::move(w));
  }
  return fits;
}

// Fits a structure of `kind` on each selected axis with its drift σ (header:
// Walks, Second-order pairs): the screen's first EM step from each start,
// the kept axes jointly from their best starts, each tested against the
// model without it.
absl::StatusOr<DriftLikelihoodResult> FitStructures(const EpochRun& run, const ErrorModel& model,
                                                    const ErrorModel& a_priori,
                                                    const DriftSelection& axes,
                                                    const StructureKind& kind, double screen_alpha,
                                                    const DriftCeilings& ceilings,
                                                    const DriftLikelihoodOptions& options) {
  if (auto st = ValidateOptions(options); !st.ok()) return st;
  DriftLikelihoodResult out;
  out.model = model;
  out.converged = true;
  const std::vector<Kind> kinds = kind.Kinds();
  const auto per_axis =
      static_cast<Eigen::Index>(kinds.size()) + 1;  // the drift σ, then the structure's

  std::vector<DriftAxis> candidates;
  for (const DriftAxis d : DriftAxis::All()) {
    if (axes.Contains(d) && HasDrift(model, d) && EffectOf(model, kind.Name(d)) < 0) {
      candidates.push_back(d);
      out.screened.Set(d);
    }
  }
  if (candidates.empty()) return out;
  auto screen = ScreenStructureStarts(run, model, a_priori, candidates, kind, options, out);
  if (!screen.ok()) return screen.status();
  const std::vector<DriftAxis>& kept_axes = screen->kept_axes;
  if (kept_axes.empty()) return out;

  // The kept structures with their drifts, jointly, each from its best start.
  ErrorModel joint = model;
  std::vector<Parameter> kept;
  for (const DriftAxis d : kept_axes) {
    auto effect = kind.At(d, screen->best_start[static_cast<size_t>(d.Index())],
                          SpecifiedDrift(model, a_priori, d), options);
    if (!effect.ok()) return effect.status();
    joint.effects.push_back(*effect);
    kept.push_back({Kind::kSigma, d});
    for (Kind k : kinds) kept.push_back({k, d});
  }
  // A pair's joint fit is capped (options): past the cap its statistic is a
  // lower bound. A structure significant at the cap is fitted on to
  // convergence before its errors are taken: the information is that of
  // the maximum, not of a point on the way to it.
  DriftLikelihoodOptions capped = options;
  if (kind.second_order)
    capped.max_iterations = std::min(options.max_iterations, options.second_order_max_iterations);
  Maximiser em(run, joint, kept, capped, out);
  auto theta = FitInto(em, out, nullptr);
  if (!theta.ok()) return theta.status();

  auto tested = TestEachWithoutIt(run, model, kept_axes, kind, options, out);
  if (!tested.ok()) return tested.status();
  std::vector<StructureEstimate> fits = std::move(*tested);
  auto significant = [&](const StructureEstimate& w) { return NestedPValue(w) < screen_alpha; };
  if (!out.converged && std::any_of(fits.begin(), fits.end(), significant)) {
    const int capped_iterations = out.iterations;
    Maximiser on(run, out.model, kept, options, out);
    theta = FitInto(on, out, nullptr);
    if (!theta.ok()) return theta.status();
    out.iterations += capped_iterations;
    for (StructureEstimate& w : fits) {
      w.statistic = std::max(0.0, 2.0 * (out.log_likelihood_after - w.log_likelihood_without));
    }
  }
  const double l_hat = out.log_likelihood_after;
  Maximiser at_estimate(run, out.model, kept, options, out);
  // From the smoother's moments, the blocks of every structure the nested
  // test keeps in one set of passes.
  std::vector<Eigen::Index> kept_blocks;
  if (options.information == DriftLikelihoodOptions::Information::kSmootherMoments) {
    for (size_t c = 0; c < fits.size(); ++c) {
      if (!significant(fits[c])) continue;
      for (Eigen::Index k = 0; k < per_axis; ++k) kept_blocks.push_back(static_cast<Eigen::Index>(c) * per_axis + k);
    }
  }
  Eigen::MatrixXd kept_information;
  if (!kept_blocks.empty()) {
    auto information = at_estimate.MomentInformation(*theta, kept_blocks);
    if (!information.ok()) return information.status();
    kept_information = *std::move(information);
  }
  Eigen::Index kept_row = 0;
  for (size_t c = 0; c < fits.size(); ++c) {
    StructureEstimate& w = fits[c];
    const auto first = static_cast<Eigen::Index>(c) * per_axis;
    w.fitted = out.model.effects[static_cast<size_t>(EffectOf(out.model, w.effect))];
    // Its errors with the drift σ's (and a pair's with each other): over a
    // bench run they trade along ridges of the likelihood, and one
    // parameter's curvature alone would hide it. Only for a structure the
    // nested test keeps: the block costs r(r + 1) passes.
    Eigen::MatrixXd covariance = Eigen::MatrixXd::Constant(per_axis, per_axis, std::numeric_limits<double>::quiet_NaN());
    if (significant(w)) {
      if (!kept_blocks.empty()) {
        covariance = StructureCovariance(kept_information.block(kept_row, kept_row, per_axis, per_axis));
        kept_row += per_axis;
      } else {
        std::vector<Eigen::Index> block;
        for (Eigen::Index k = 0; k < per_axis; ++k) block.push_back(first + k);
        auto information = at_estimate.BlockInformation(*theta, block, l_hat);
        if (!information.ok()) return information.status();
        covariance = StructureCovariance(*information);
      }
    }
    auto estimate = [&](Eigen::Index k) {
      return EstimateOf(kept[static_cast<size_t>(first + k)], std::exp((*theta)[first + k]), std::sqrt(covariance(k, k)),
                        a_priori);
    };
    w.drift_sigma = estimate(0);
    w.refused_by_raw_samples = StructureRefused(out.model, w, ceilings);
    std::vector<ParameterEstimate> fitted;
    for (Eigen::Index k = 1; k < per_axis; ++k) fitted.push_back(estimate(k));
    w.parameters = ReportedParameters(kind, w.drift, fitted);
    out.identified.insert(out.identified.end(), w.parameters.begin(), w.parameters.end());
    out.structures.push_back(std::move(w));
  }
  return out;
}

}  // namespace

Eigen::MatrixXd StructureCovariance(const Eigen::MatrixXd& information) {
  const Eigen::Index n = information.rows();
  Eigen::MatrixXd covariance = Eigen::MatrixXd::Constant(n, n, std::numeric_limits<double>::infinity());
  const Eigen::LLT<Eigen::MatrixXd> llt(information);
  if (llt.info() == Eigen::Success) return llt.solve(Eigen::MatrixXd::Identity(n, n));
  if (n > 1 && information(0, 0) <= 0.0) {
    const Eigen::Index r = n - 1;
    const Eigen::LLT<Eigen::MatrixXd> own(information.bottomRightCorner(r, r));
    if (own.info() == Eigen::Success) covariance.bottomRightCorner(r, r) = own.solve(Eigen::MatrixXd::Identity(r, r));
  }
  return covariance;
}

absl::StatusOr<DriftInformation> ObservedDriftInformation(const EpochRun& run, const ErrorModel& model,
                                                          const std::vector<std::string>& names,
                                                          const DriftLikelihoodOptions& options) {
  if (auto st = ValidateOptions(options); !st.ok()) return st;
  std::vector<Parameter> candidates;
  for (const DriftAxis d : DriftAxis::All()) {
    if (HasDrift(model, d)) {
      candidates.push_back({Kind::kSigma, d});
      candidates.push_back({Kind::kTau, d});
    }
    if (WalkEffectOf(model, d) >= 0) candidates.push_back({Kind::kWalk, d});
    if (PairEffectOf(model, d) >= 0) {
      for (Kind k : {Kind::kPairSigma, Kind::kPairDecayRate, Kind::kPairFrequency}) candidates.push_back({k, d});
    }
  }
  std::vector<Parameter> parameters;
  for (const std::string& name : names) {
    const auto found = std::find_if(candidates.begin(), candidates.end(),
                                    [&](const Parameter& p) { return NameOf(p) == name; });
    if (found == candidates.end())
      return absl::InvalidArgumentError("drift information: the model has no parameter " + name);
    parameters.push_back(*found);
  }
  // A τ is differentiated with its σ, a pair's α and β with its σ₂.
  auto named = [&](Kind kind, DriftAxis d) {
    return std::any_of(parameters.begin(), parameters.end(),
                       [&](const Parameter& p) { return p.kind == kind && p.drift == d; });
  };
  for (const Parameter& p : parameters) {
    const bool needs_sigma = p.kind == Kind::kTau && !named(Kind::kSigma, p.drift);
    const bool needs_pair_sigma = (p.kind == Kind::kPairDecayRate || p.kind == Kind::kPairFrequency) &&
                                  !named(Kind::kPairSigma, p.drift);
    if (needs_sigma || needs_pair_sigma)
      return absl::InvalidArgumentError("drift information: " + NameOf(p) + " without its σ");
  }
  DriftLikelihoodResult passes;
  Maximiser em(run, model, parameters, options, passes);
  const Eigen::VectorXd theta = em.Start();
  std::vector<Eigen::Index> every(parameters.size());
  for (size_t j = 0; j < parameters.size(); ++j) every[j] = static_cast<Eigen::Index>(j);
  DriftInformation out;
  if (options.information == DriftLikelihoodOptions::Information::kSmootherMoments) {
    auto information = em.MomentInformation(theta, every);
    if (!information.ok()) return information.status();
    out.information = *std::move(information);
  } else {
    auto l0 = em.LogLikelihood(model);
    if (!l0.ok()) return l0.status();
    auto information = em.BlockInformation(theta, every, *l0);
    if (!information.ok()) return information.status();
    out.information = *std::move(information);
  }
  out.filter_passes = passes.filter_passes;
  return out;
}

absl::StatusOr<DriftLikelihoodResult> IdentifyWalksByLikelihood(const EpochRun& run, const ErrorModel& model,
                                                                const ErrorModel& a_priori,
                                                                const DriftSelection& axes, double screen_alpha,
                                                                const DriftCeilings& ceilings,
                                                                const DriftLikelihoodOptions& options) {
  return FitStructures(run, model, a_priori, axes, StructureKind{false}, screen_alpha, ceilings, options);
}

absl::StatusOr<DriftLikelihoodResult> IdentifySecondOrdersByLikelihood(const EpochRun& run, const ErrorModel& model,
                                                                       const ErrorModel& a_priori,
                                                                       const DriftSelection& axes,
                                                                       double screen_alpha,
                                                                       const DriftCeilings& ceilings,
                                                                       const DriftLikelihoodOptions& options) {
  if (options.second_order_start_periods_s.empty() ||
      std::any_of(options.second_order_start_periods_s.begin(), options.second_order_start_periods_s.end(),
                  [](double p) { return !(p > 0.0); })) {
    return absl::InvalidArgumentError("drift likelihood: second-order starting periods must be positive");
  }
  return FitStructures(run, model, a_priori, axes, StructureKind{true}, screen_alpha, ceilings, options);
}

}  // namespace insdiag::engine::ident
