#include "analysis/noise_identification.h"

#include <absl/strings/str_format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string_view>

#include "analysis/model_pass.h"
#include "insdiag/engine/ident/retarget.h"
#include "insdiag/engine/model/drift_axis.h"
#include "insdiag/engine/numerics/golden_section.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine::pipeline {

std::vector<ParameterEstimate> ApplyAllanNoise(const RunContext& c, const ident::AllanResult& allan,
                                               ErrorModel& base) {
  std::vector<ParameterEstimate> identified =
      ident::ApplyAllanNoise(allan, c.a_priori.model, base, c.options.monitor.family_wise_alpha);
  for (const ParameterEstimate& p : ident::AllanParameterEstimates(allan, &c.a_priori.model)) {
    if (!DriftOfParameter(p.name).has_value() &&
        std::none_of(identified.begin(), identified.end(),
                     [&](const ParameterEstimate& q) { return q.name == p.name; })) {
      identified.push_back(p);
    }
  }
  return identified;
}

void KeepQuantisationTheInnovationsSupport(const RunContext& c, QuantisationTest when,
                                           ErrorModel& model,
                                           std::vector<ParameterEstimate>& identified,
                                           DecisionLog& decisions) {
  Eigen::Vector3d stated = c.a_priori.FromAllanFit() ? Eigen::Vector3d::Zero()
                                                 : Eigen::Vector3d(c.a_priori.model.acc.quantization);
  for (int axis = 0; axis < 3; ++axis) {
    const double counted =
        c.a_priori.counted_quantisation[static_cast<size_t>(DriftAxis{Sensor::kAccelerometer, axis}.Index())];
    stated[axis] = std::max(stated[axis], counted);
  }
  if (model.acc.quantization == stated) return;
  ErrorModel without = model;
  without.acc.quantization = stated;
  const auto with_it = ProfileLogLikelihood(c.epochs, model);
  const auto without_it = ProfileLogLikelihood(c.epochs, without);
  if (!with_it.ok() || !without_it.ok()) return;
  Decision d;
  d.kind = DecisionKind::kQuantisationKept;
  d.statistic = 2.0 * (*with_it - *without_it);
  d.adopted = d.statistic > 0.0;
  d.qualifiers = {when == QuantisationTest::kBeforeTheDrifts ? "before_the_drifts" : "after_the_drifts"};
  d.rejected = {{"the model without it", -d.statistic}};
  for (int axis = 0; axis < 3; ++axis) {
    if (model.acc.quantization[axis] == stated[axis]) continue;
    d.subjects.push_back(QuantizationName({Sensor::kAccelerometer, axis}));
    d.measures.emplace_back(d.subjects.back(), model.acc.quantization[axis]);
  }
  if (d.adopted) {
    // Kept before the drifts is weighed again after them; the report says the last.
    if (when == QuantisationTest::kAfterTheDrifts) decisions.Record(std::move(d));
    return;
  }
  model = std::move(without);
  for (int axis = 0; axis < 3; ++axis) {
    const std::string name = QuantizationName({Sensor::kAccelerometer, axis});
    std::erase_if(identified, [&](const ParameterEstimate& p) { return p.name == name; });
  }
  decisions.Record(std::move(d));
}

bool FitReferenceNoiseTheInnovationsReject(const RunContext& c, const ForwardPass& forward,
                                           const ErrorModel& passed, ErrorModel& model,
                                           DecisionLog& decisions) {
  const double alpha = c.options.monitor.family_wise_alpha;
  const ident::ReferenceNoiseExcess excess = ident::ScreenReferenceNoise(forward, alpha, passed);
  if (!excess.Any()) return false;
  ErrorModel fitted = passed;
  const double before = ProfileLogLikelihood(forward, passed);
  double best = before;
  int fitted_groups = 0;
  absl::Status failure = absl::OkStatus();
  for (size_t group = 0; group < ident::kReferenceChannelGroups.size(); ++group) {
    const ident::ReferenceChannelGroup& g = ident::kReferenceChannelGroups[group];
    const std::optional<double>& matched = excess.matched_sigma[group];
    if (!matched.has_value()) continue;
    ++fitted_groups;
    double& sigma = fitted.reference.*g.sigma;
    const double lowest = std::log(sigma);
    const auto log_likelihood_at = [&](double log_sigma) {
      sigma = std::exp(log_sigma);
      auto l = ProfileLogLikelihood(c.epochs, fitted);
      if (!l.ok()) failure = l.status();
      return l.ok() ? *l : -std::numeric_limits<double>::infinity();
    };
    const auto [top, log_sigma] =
        numerics::GoldenSectionMaximum(lowest, std::log(2.0 * *matched), lowest, best,
                                       c.options.noise_scale.log_tolerance, log_likelihood_at);
    best = top;
    sigma = std::exp(log_sigma);
  }
  if (!failure.ok()) {
    decisions.Note("the reference noise was not fitted: " + std::string(failure.message()));
    return false;
  }
  Decision d;
  d.kind = DecisionKind::kReferenceNoiseRaised;
  d.statistic = 2.0 * (best - before);
  d.degrees_of_freedom = fitted_groups;
  d.level = alpha;
  for (const ident::ReferenceChannelGroup& g : ident::kReferenceChannelGroups) {
    const double from = passed.reference.*g.sigma, to = fitted.reference.*g.sigma;
    if (to == from) continue;
    d.subjects.emplace_back(g.name);
    d.measures.emplace_back(std::string(g.name) + ".before", from);
    d.measures.emplace_back(std::string(g.name) + ".after", to);
  }
  d.adopted = d.statistic > stats::ChiSquareQuantile(1.0 - alpha, fitted_groups);
  if (d.adopted) model.reference = fitted.reference;
  const bool raised = d.adopted;
  decisions.Record(std::move(d));
  return raised;
}

void RetuneUnresolvedNoise(const RunContext& c, const std::optional<ident::AllanResult>& allan,
                           ErrorModel& base, std::vector<ParameterEstimate>& identified,
                           DecisionLog& decisions) {
  const ident::UnresolvedNoise unresolved = c.a_priori.FromAllanFit() && allan.has_value()
                                                ? ident::UnresolvedAllanTerms(*allan)
                                                : ident::UnresolvedNoise{};
  if (!unresolved.Any()) return;
  Progress(c.options, 0.08, "maximum-likelihood noise scale");
  auto scaled = ident::ScaleUnresolvedNoise(c.epochs, base, unresolved, c.options.noise_scale);
  if (!scaled.ok()) {
    decisions.Note("the noise terms set from Allan bounds were not re-tuned: " +
                    std::string(scaled.status().message()));
    return;
  }
  base = scaled->model;
  for (const ident::NoiseScaleGroup& g : scaled->groups) {
    const bool seeded = g.name.ends_with("seed");
    const bool white = g.name.find("white") != std::string::npos;
    Decision d;
    d.kind = DecisionKind::kNoiseRetuned;
    d.subjects = g.terms;
    d.scope = g.name;
    d.adopted = true;
    d.measures = {{"scale", g.scale}, {"log_std_error", g.log_std_error}};
    d.qualifiers.emplace_back(seeded && white ? "resolved_by_the_allan_fit"
                              : seeded        ? "seeded_by_the_allan_fit"
                                              : "set_from_allan_bounds");
    if (g.at_limit) d.qualifiers.emplace_back("at_the_search_limit");
    decisions.Record(std::move(d));
  }
  decisions.Note(absl::StrFormat(
      "the innovations' log-likelihood rose by %.1f after %d filter passes",
      scaled->log_likelihood_after - scaled->log_likelihood_before, scaled->filter_passes));
  for (const ParameterEstimate& p : scaled->identified) {
    std::erase_if(identified, [&](const ParameterEstimate& q) { return q.name == p.name; });
    identified.push_back(p);
  }
}

absl::Status FitReferenceNoiseToTheIdentifiedModel(const RunContext& c, ErrorModel& model,
                                                   DecisionLog& decisions) {
  auto pass = RunForwardFilter(c.epochs, model);
  if (!pass.ok()) return pass.status();
  const ErrorModel passed = model;
  FitReferenceNoiseTheInnovationsReject(c, *pass, passed, model, decisions);
  return absl::OkStatus();
}

}  // namespace insdiag::engine::pipeline
