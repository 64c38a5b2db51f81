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
                                           std::vector<std::string>& notes) {
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
  const double statistic = 2.0 * (*with_it - *without_it);
  std::string axes;
  for (int axis = 0; axis < 3; ++axis) {
    if (model.acc.quantization[axis] == stated[axis]) continue;
    absl::StrAppendFormat(&axes, "%s%s %.3g m/s", axes.empty() ? "" : ", ",
                          AxisLabel(AxisSet::kSingle, axis, axis), model.acc.quantization[axis]);
  }
  const std::string_view against =
      when == QuantisationTest::kBeforeTheDrifts ? "the a-priori drifts" : "the identified drifts";
  if (statistic > 0.0) {
    if (when == QuantisationTest::kAfterTheDrifts) {
      notes.push_back(
          absl::StrFormat("the Allan fit's accelerometer quantisation (%s) is in the model: "
                          "with %s the innovations' likelihood prefers it, 2Δℓ = %.1f",
                          axes, against, statistic));
    }
    return;
  }
  model = std::move(without);
  for (int axis = 0; axis < 3; ++axis) {
    const std::string name = QuantizationName({Sensor::kAccelerometer, axis});
    std::erase_if(identified, [&](const ParameterEstimate& p) { return p.name == name; });
  }
  notes.push_back(
      absl::StrFormat("the Allan fit's accelerometer quantisation (%s) is not in the model: "
                      "with %s the innovations' likelihood is higher without it (2Δℓ = %.1f); "
                      "over the static segments' few short cluster times it stood for the "
                      "white noise and the drift's rise",
                      axes, against, -statistic));
}

bool FitReferenceNoiseTheInnovationsReject(const RunContext& c, const ForwardPass& forward,
                                           const ErrorModel& passed, ErrorModel& model,
                                           std::vector<std::string>& notes) {
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
    notes.push_back("the reference noise was not fitted: " + std::string(failure.message()));
    return false;
  }
  std::string changes;
  for (const ident::ReferenceChannelGroup& g : ident::kReferenceChannelGroups) {
    const double from = passed.reference.*g.sigma, to = fitted.reference.*g.sigma;
    if (to != from) {
      absl::StrAppendFormat(&changes, "%s%s %.3g → %.3g %s", changes.empty() ? "" : ", ", g.name,
                            from, to, g.unit);
    }
  }
  const double statistic = 2.0 * (best - before);
  const double critical = stats::ChiSquareQuantile(1.0 - alpha, fitted_groups);
  if (statistic > critical) {
    model.reference = fitted.reference;
    notes.push_back(absl::StrFormat(
        "the innovations exceed their predicted variance: the reference noise was raised by "
        "maximum likelihood (%s; 2Δℓ = %.1f against χ²(%d) at %.2g) — the unit moved in ways "
        "the bench's reference did not record (sway, vibration)",
        changes, statistic, fitted_groups, alpha));
    return true;
  }
  notes.push_back(absl::StrFormat(
      "the innovations exceed their predicted variance, but not as a noise of the bench's "
      "reference: its likelihood's best value%s gains 2Δℓ = %.1f against χ²(%d) at %.2g; "
      "the reference accuracy is kept",
      changes.empty() ? "" : " (" + changes + ")", statistic, fitted_groups, alpha));
  return false;
}

void RetuneUnresolvedNoise(const RunContext& c, const std::optional<ident::AllanResult>& allan,
                           ErrorModel& base, std::vector<ParameterEstimate>& identified,
                           std::vector<std::string>& notes) {
  const ident::UnresolvedNoise unresolved = c.a_priori.FromAllanFit() && allan.has_value()
                                                ? ident::UnresolvedAllanTerms(*allan)
                                                : ident::UnresolvedNoise{};
  if (!unresolved.Any()) return;
  Progress(c.options, 0.08, "maximum-likelihood noise scale");
  auto scaled = ident::ScaleUnresolvedNoise(c.epochs, base, unresolved, c.options.noise_scale);
  if (!scaled.ok()) {
    notes.push_back("the noise terms set from Allan bounds were not re-tuned: " +
                    std::string(scaled.status().message()));
    return;
  }
  base = scaled->model;
  for (const ident::NoiseScaleGroup& g : scaled->groups) {
    std::string terms;
    for (const std::string& t : g.terms) terms += (terms.empty() ? "" : ", ") + t;
    const bool seeded = g.name.ends_with("seed");
    const bool white = g.name.find("white") != std::string::npos;
    notes.push_back("re-tuned by maximum likelihood of the innovations, " + g.name + " (" + terms +
                    (seeded && white ? ", resolved by the Allan fit of the raw samples): "
                     : seeded        ? ", seeded by the Allan fit, not resolved by correlation processing): "
                            : ", set from Allan bounds): ") +
                    absl::StrFormat("× %.3g (SE of ln: %.2g)%s", g.scale, g.log_std_error,
                                    g.at_limit ? ", at the search range's limit" : ""));
  }
  notes.push_back(absl::StrFormat(
      "the innovations' log-likelihood rose by %.1f after %d filter passes",
      scaled->log_likelihood_after - scaled->log_likelihood_before, scaled->filter_passes));
  for (const ParameterEstimate& p : scaled->identified) {
    std::erase_if(identified, [&](const ParameterEstimate& q) { return q.name == p.name; });
    identified.push_back(p);
  }
}

absl::Status FitReferenceNoiseToTheIdentifiedModel(const RunContext& c, ErrorModel& model,
                                                   std::vector<std::string>& notes) {
  auto pass = RunForwardFilter(c.epochs, model);
  if (!pass.ok()) return pass.status();
  const ErrorModel passed = model;
  FitReferenceNoiseTheInnovationsReject(c, *pass, passed, model, notes);
  return absl::OkStatus();
}

}  // namespace insdiag::engine::pipeline
