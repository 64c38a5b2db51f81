#include "insdiag/kb/reliability.h"

#include <absl/strings/str_cat.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include "insdiag/engine/stats/distributions.h"

namespace insdiag::kb {
namespace {

// Sums over all lives in units of the longest life (t/t_max ≤ 1 keeps t^β finite).
struct Sums {
  double w = 0.0;     // Σ s^β
  double wl = 0.0;    // Σ s^β ln s
  double wll = 0.0;   // Σ s^β (ln s)²
};

Sums PowerSums(std::span<const double> log_s, double beta) {
  Sums sums;
  for (double l : log_s) {
    const double w = std::exp(beta * l);
    sums.w += w;
    sums.wl += w * l;
    sums.wll += w * l * l;
  }
  return sums;
}

}  // namespace

absl::StatusOr<WeibullEstimate> FitWeibull(std::span<const LifeObservation> lives, double confidence) {
  if (!(confidence > 0.0 && confidence < 1.0)) {
    return absl::InvalidArgumentError(absl::StrCat("confidence must be within (0, 1), not ", confidence));
  }
  double t_max = 0.0;
  std::int64_t r = 0;
  std::set<double> failure_times;
  for (const auto& life : lives) {
    if (!(life.hours > 0.0) || !std::isfinite(life.hours)) {
      return absl::InvalidArgumentError(absl::StrCat("a life of ", life.hours, " h: lives must be positive"));
    }
    t_max = std::max(t_max, life.hours);
    if (life.failed) {
      ++r;
      failure_times.insert(life.hours);
    }
  }
  if (r < 2 || failure_times.size() < 2) {
    return absl::FailedPreconditionError(
        absl::StrCat("a Weibull fit needs at least 2 failures at distinct times; there are ", r));
  }
  std::vector<double> log_s;  // ln(t/t_max) of all lives
  double sum_log_failed = 0.0;
  for (const auto& life : lives) {
    log_s.push_back(std::log(life.hours / t_max));
    if (life.failed) sum_log_failed += log_s.back();
  }
  const double rd = static_cast<double>(r);
  const auto score = [&](double beta) {
    const Sums s = PowerSums(log_s, beta);
    return 1.0 / beta + sum_log_failed / rd - s.wl / s.w;
  };
  // g decreases from +∞ (β → 0) to the negative mean spread: bracket, bisect, polish.
  double lo = 1e-3, hi = 1.0;
  while (score(hi) > 0.0 && hi < 1e3) hi *= 2.0;
  if (score(hi) > 0.0) return absl::FailedPreconditionError("the Weibull shape estimate diverges (no spread of failure times)");
  for (int i = 0; i < 200 && hi - lo > 1e-12 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (score(mid) > 0.0 ? lo : hi) = mid;
  }
  double beta = 0.5 * (lo + hi);
  for (int i = 0; i < 3; ++i) {  // Newton: g'(β) = −1/β² − (Σw l² Σw − (Σw l)²)/(Σw)²
    const Sums s = PowerSums(log_s, beta);
    const double g = 1.0 / beta + sum_log_failed / rd - s.wl / s.w;
    const double dg = -1.0 / (beta * beta) - (s.wll * s.w - s.wl * s.wl) / (s.w * s.w);
    const double next = beta - g / dg;
    if (next > 0.0 && std::isfinite(next)) beta = next;
  }
  const Sums s = PowerSums(log_s, beta);
  const double eta_scaled = std::pow(s.w / rd, 1.0 / beta);  // η / t_max
  const double eta = eta_scaled * t_max;

  // Observed information in (β, η) at the estimate, with u = ln(t/η), w = (t/η)^β.
  double sw = 0.0, swu = 0.0, swuu = 0.0;
  for (std::size_t i = 0; i < lives.size(); ++i) {
    const double u = log_s[i] - std::log(eta_scaled);
    const double w = std::exp(beta * u);
    sw += w;
    swu += w * u;
    swuu += w * u * u;
  }
  const double h_bb = -rd / (beta * beta) - swuu;
  const double h_ee = (beta / (eta * eta)) * (rd - sw) - (beta * beta / (eta * eta)) * sw;
  const double h_be = (-rd + sw + beta * swu) / eta;
  // Covariance = (−H)⁻¹.
  const double a = -h_bb, b = -h_be, d = -h_ee;
  const double det = a * d - b * b;
  if (!(det > 0.0)) return absl::FailedPreconditionError("the Weibull information matrix is singular");
  const double var_beta = d / det, var_eta = a / det, cov = -b / det;

  WeibullEstimate out;
  out.failures = r;
  out.suspensions = static_cast<std::int64_t>(lives.size()) - r;
  out.shape = beta;
  out.scale_hours = eta;
  out.shape_std_error = std::sqrt(var_beta);
  out.scale_std_error_hours = std::sqrt(var_eta);
  const double z = engine::stats::NormalQuantile(0.5 + 0.5 * confidence);
  out.shape_lower = beta * std::exp(-z * out.shape_std_error / beta);
  out.shape_upper = beta * std::exp(z * out.shape_std_error / beta);
  out.scale_lower_hours = eta * std::exp(-z * out.scale_std_error_hours / eta);
  out.scale_upper_hours = eta * std::exp(z * out.scale_std_error_hours / eta);
  const double k = std::log(-std::log(0.9));  // ln(−ln 0.9)
  out.b10_hours = eta * std::exp(k / beta);
  // ∂ ln B10 / ∂β = −k/β², ∂ ln B10 / ∂η = 1/η.
  const double gb = -k / (beta * beta), ge = 1.0 / eta;
  const double var_log_b10 = gb * gb * var_beta + 2.0 * gb * ge * cov + ge * ge * var_eta;
  out.b10_lower_hours = out.b10_hours * std::exp(-z * std::sqrt(var_log_b10));
  out.b10_upper_hours = out.b10_hours * std::exp(z * std::sqrt(var_log_b10));
  out.log_likelihood = rd * std::log(beta) - rd * beta * std::log(eta) + (beta - 1.0) * (sum_log_failed + rd * std::log(t_max)) - sw;
  return out;
}

MtbfEstimate EstimateMtbf(double exposure_hours, std::int64_t failures, double confidence) {
  MtbfEstimate out;
  if (exposure_hours <= 0.0 || !(confidence > 0.0 && confidence < 1.0)) return out;
  const double alpha = 1.0 - confidence;
  const double r = static_cast<double>(failures);
  out.lower_hours = 2.0 * exposure_hours / engine::stats::ChiSquareQuantile(1.0 - alpha / 2.0, 2.0 * r + 2.0);
  if (failures > 0) {
    out.mtbf_hours = exposure_hours / r;
    out.upper_hours = 2.0 * exposure_hours / engine::stats::ChiSquareQuantile(alpha / 2.0, 2.0 * r);
  }
  return out;
}

}  // namespace insdiag::kb
