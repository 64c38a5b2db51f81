#include "insdiag/engine/ident/drift_likelihood.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <Eigen/Core>

#include "insdiag/engine/filter/smoother.h"
#include "insdiag/engine/model/state_layout.h"

namespace insdiag::engine::ident {
namespace {

GaussMarkov& DriftOf(ErrorModel& m, int drift) {
  return (drift < 3 ? m.gyro : m.acc).bias[static_cast<size_t>(drift % 3)];
}
const GaussMarkov& DriftOf(const ErrorModel& m, int drift) {
  return (drift < 3 ? m.gyro : m.acc).bias[static_cast<size_t>(drift % 3)];
}

}  // namespace

std::string DriftName(int drift) {
  return std::string(drift < 3 ? "gyro_bias_gm." : "acc_bias_gm.") + "xyz"[drift % 3];
}

absl::StatusOr<DriftLikelihoodResult> IdentifyDriftsByLikelihood(const BenchRun& run, const ErrorModel& model,
                                                                 const ErrorModel& a_priori,
                                                                 const DriftSelection& which,
                                                                 const FilterOptions& filter,
                                                                 const DriftLikelihoodOptions& options) {
  if (!(options.max_iterations > 0 && options.log_tolerance > 0.0 && options.curvature_step > 0.0)) {
    return absl::InvalidArgumentError("drift likelihood options out of range");
  }
  DriftLikelihoodResult out;
  out.model = model;
  const StateLayout layout(model);
  std::vector<int> drifts;
  for (int d = 0; d < 6; ++d) {
    // A drift the model leaves out (σ = 0) has no state to identify.
    if (which[static_cast<size_t>(d)] && DriftOf(model, d).sigma > 0.0 && DriftOf(model, d).tau_s > 0.0) {
      drifts.push_back(d);
    }
  }
  auto forward = [&](const ErrorModel& m) -> absl::StatusOr<ForwardPass> {
    ++out.filter_passes;
    return RunForwardFilter(run, m, filter);
  };
  if (drifts.empty()) {
    out.converged = true;
    return out;
  }

  // θ: ln σ of each selected drift, in `drifts` order.
  const auto m = static_cast<Eigen::Index>(drifts.size());
  auto model_of = [&](const Eigen::VectorXd& theta) {
    ErrorModel result = model;
    for (Eigen::Index j = 0; j < m; ++j) DriftOf(result, drifts[static_cast<size_t>(j)]).sigma = std::exp(theta[j]);
    return result;
  };
  // One EM step from θ: ℓ(θ) and the M-step's θ (header).
  struct Step {
    double log_likelihood;
    Eigen::VectorXd next;
  };
  auto em_step = [&](const Eigen::VectorXd& theta) -> absl::StatusOr<Step> {
    auto fw = forward(model_of(theta));
    if (!fw.ok()) return fw.status();
    const int K = fw->epochs();
    if (K < 3) return absl::InvalidArgumentError("drift likelihood: the run has fewer than three epochs");
    auto sm = RunSmoother(*fw);
    if (!sm.ok()) return sm.status();
    const double dt = (fw->epoch_time_s.back() - fw->epoch_time_s.front()) / (K - 1);
    Step step{fw->log_likelihood, theta};
    for (Eigen::Index j = 0; j < m; ++j) {
      const int d = drifts[static_cast<size_t>(j)];
      const int state = layout.gyro_bias() + d;
      double a_from = 0.0, a_to = 0.0, b = 0.0;
      for (int k = 0; k + 1 < K; ++k) {
        const double x0 = sm->x(k, state), x1 = sm->x(k + 1, state);
        a_from += x0 * x0 + sm->variance(k, state);
        a_to += x1 * x1 + sm->variance(k + 1, state);
        b += x1 * x0 + sm->lag_one_covariance(k, state);
      }
      const double a0 = sm->x(0, state) * sm->x(0, state) + sm->variance(0, state);
      const double phi = std::exp(-dt / DriftOf(model, d).tau_s);
      const double sigma2 = (a0 + (a_to - 2.0 * phi * b + phi * phi * a_from) / (1.0 - phi * phi)) / K;
      if (sigma2 > 0.0) step.next[j] = 0.5 * std::log(sigma2);
    }
    return step;
  };

  // SQUAREM, scheme S3 (Varadhan & Roland 2008): two EM steps give
  // r = θ₁ − θ₀ and v = θ₂ − 2θ₁ + θ₀; with α = −‖r‖/‖v‖ (at most −1, which
  // is θ₂ itself) θ′ = θ₀ − 2αr + α²v, whose EM step continues the cycle when
  // its likelihood is not below θ₂'s. A step length per drift: the drifts are
  // near-independent, and one that crawls must not wait for the others.
  Eigen::VectorXd theta(m);
  for (Eigen::Index j = 0; j < m; ++j) theta[j] = std::log(DriftOf(model, drifts[static_cast<size_t>(j)]).sigma);
  for (int cycle = 0; out.iterations < options.max_iterations; ++cycle) {
    auto first = em_step(theta);
    if (!first.ok()) return first.status();
    if (cycle == 0) out.log_likelihood_before = first->log_likelihood;
    auto second = em_step(first->next);
    if (!second.ok()) return second.status();
    out.iterations += 2;
    const Eigen::VectorXd r = first->next - theta;
    const Eigen::VectorXd v = second->next - first->next - r;
    Eigen::VectorXd next = second->next;
    Eigen::VectorXd extrapolated = second->next;
    bool extrapolates = false;
    for (Eigen::Index j = 0; j < m; ++j) {
      if (!(std::abs(v[j]) > 0.0)) continue;
      const double alpha = std::min(-1.0, -std::abs(r[j]) / std::abs(v[j]));
      extrapolated[j] = theta[j] - 2.0 * alpha * r[j] + alpha * alpha * v[j];
      extrapolates = extrapolates || alpha < -1.0;
    }
    if (extrapolates) {
      auto third = em_step(extrapolated);
      if (!third.ok()) return third.status();
      ++out.iterations;
      if (third->log_likelihood >= second->log_likelihood) next = third->next;
    }
    const double largest_step = (next - theta).cwiseAbs().maxCoeff();
    theta = next;
    if (largest_step < options.log_tolerance) {
      out.converged = true;
      break;
    }
  }
  out.model = model_of(theta);

  // ℓ at the estimate and its curvature in ln σ per drift (observed information).
  auto at_estimate = forward(out.model);
  if (!at_estimate.ok()) return at_estimate.status();
  const double l0 = at_estimate->log_likelihood;
  out.log_likelihood_after = l0;
  const double h = options.curvature_step;
  bool any_flat = false;
  for (Eigen::Index j = 0; j < m; ++j) {
    const int d = drifts[static_cast<size_t>(j)];
    double shifted[2];
    for (int side = 0; side < 2; ++side) {
      Eigen::VectorXd probe = theta;
      probe[j] += side == 0 ? h : -h;
      auto fw = forward(model_of(probe));
      if (!fw.ok()) return fw.status();
      shifted[side] = fw->log_likelihood;
    }
    const double information = -(shifted[0] - 2.0 * l0 + shifted[1]) / (h * h);
    if (!(information > 0.0)) {
      // The likelihood is flat in this σ: the run's motion does not make the
      // drift observable (a level gyro's heading drift on a still table). Not
      // an estimate — the model keeps its value.
      DriftOf(out.model, d).sigma = DriftOf(model, d).sigma;
      out.not_identifiable.push_back(DriftName(d) + ".sigma");
      any_flat = true;
      continue;
    }
    const double log_se = 1.0 / std::sqrt(information);
    ParameterEstimate e;
    e.name = DriftName(d) + ".sigma";
    e.value = std::exp(theta[j]);
    e.std_error = e.value * log_se;
    e.ci95_low = e.value * std::exp(-1.96 * log_se);
    e.ci95_high = e.value * std::exp(1.96 * log_se);
    e.method = "ML";
    e.unit = d < 3 ? "rad/s" : "m/s^2";
    e.a_priori = DriftOf(a_priori, d).sigma;
    out.identified.push_back(e);
  }
  if (any_flat) {
    auto kept = forward(out.model);
    if (!kept.ok()) return kept.status();
    out.log_likelihood_after = kept->log_likelihood;
  }
  return out;
}

}  // namespace insdiag::engine::ident
