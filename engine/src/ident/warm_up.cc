#include "insdiag/engine/ident/warm_up.h"

#include <Eigen/LU>

#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "insdiag/engine/filter/epoch_run.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/nav/rotation.h"
#include "insdiag/engine/nav/wgs84.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine::ident {
namespace {

using Vector6d = Eigen::Matrix<double, 6, 1>;

// The run's still start: the samples from the first while the reference
// attitude stays within `still_tolerance_rad` of the first sample's and no
// new segment begins. Returns their end (exclusive).
size_t StillStartEnd(const BenchRun& run, double still_tolerance_rad) {
  const Eigen::Vector3d& start_rpy = run.samples.front().ref_rpy_rad;
  size_t k = 1;
  for (; k < run.samples.size() && !run.StartsSegment(k); ++k) {
    const Eigen::Vector3d& rpy = run.samples[k].ref_rpy_rad;
    bool still = true;
    for (int i = 0; i < 3; ++i) {
      still = still && std::abs(std::remainder(rpy[i] - start_rpy[i], 2.0 * std::numbers::pi)) <= still_tolerance_rad;
    }
    if (!still) break;
  }
  return k;
}

// What a perfect unit reads at rest in the run's first reference attitude
// (static_constants.h): Earth's rate, then gravity's specific force, in body axes.
Vector6d PerfectReadingAtStart(const BenchRun& run) {
  const Site& site = run.metadata.site;
  const Eigen::Matrix3d C_n_b = nav::EulerToDcm(run.samples.front().ref_rpy_rad).transpose();
  Vector6d perfect;
  perfect << C_n_b * wgs84::EarthRateNed(site.latitude_rad),
      C_n_b * Eigen::Vector3d(0.0, 0.0, -wgs84::NormalGravityMps2(site.latitude_rad, site.height_m));
  return perfect;
}

// The still start's readings less a perfect unit's, averaged per update
// interval: times from the first sample and the six axes' means.
struct IntervalMeans {
  std::vector<double> t_s;  // the interval's mid-time
  std::vector<Vector6d> mean;
  double interval_s = 0.0;
};

IntervalMeans MeansOverTheQuietStillStart(const BenchRun& run, double update_interval_s, double still_tolerance_rad,
                                          std::optional<double> bench_moved_from_s) {
  IntervalMeans out;
  out.interval_s = update_interval_s;
  const size_t end = StillStartEnd(run, still_tolerance_rad);
  const double t0_s = run.samples.front().t_s;
  const double quiet_until_s = bench_moved_from_s.value_or(run.samples[end - 1].t_s);
  const Vector6d perfect = PerfectReadingAtStart(run);
  Vector6d sum = Vector6d::Zero();
  int count = 0;
  double interval_end_s = t0_s + update_interval_s;
  for (size_t k = 1; k < end && run.samples[k].t_s <= quiet_until_s; ++k) {
    const ImuSample& s = run.samples[k];
    if (s.t_s > interval_end_s) {
      if (count > 0) {
        out.t_s.push_back(interval_end_s - 0.5 * update_interval_s - t0_s);
        out.mean.push_back(sum / count);
      }
      sum.setZero();
      count = 0;
      while (s.t_s > interval_end_s) interval_end_s += update_interval_s;
    }
    Vector6d r;
    r << s.gyro_rad_s, s.acc_mps2;
    sum += r - perfect;
    ++count;
  }
  return out;
}

// Least squares of y = c + b e^{−t/τ} + b′ e^{−(T−t)/τ′} on the interval
// means of one axis (b′ = 0 and τ′ unused where `with_end` is false): b and
// b′, their variances per unit variance of a mean, and the residual sum of
// squares.
struct TransientFit {
  double b = 0.0, b_end = 0.0;
  // b and b′ as weighted sums of the interval means: Σ_j w_j ȳ_j.
  std::vector<double> b_weights, b_end_weights;
  double rss = std::numeric_limits<double>::infinity();
};

// The variance of Σ_j w_j ȳ_j where the interval means ȳ_j hold a stationary
// first-order Gauss–Markov drift (σ, τ) and white noise of variance
// `mean_variance` each: σ² Σ_j Σ_k w_j w_k e^{−|t_j − t_k|/τ} + Σ_j w_j² v,
// the double sum by one pass forward and one back (the kernel is a product
// of the steps' factors).
double VarianceUnderStationaryDrift(const std::vector<double>& w, const std::vector<double>& t_s,
                                    const GaussMarkov& drift, double mean_variance) {
  const size_t n = w.size();
  double white = 0.0;
  for (double x : w) white += x * x;
  if (!(drift.sigma > 0.0) || !(drift.tau_s > 0.0) || n == 0) return white * mean_variance;
  std::vector<double> forward(n);
  double f = 0.0;
  for (size_t j = 0; j < n; ++j) {
    f = w[j] + (j > 0 ? std::exp(-(t_s[j] - t_s[j - 1]) / drift.tau_s) * f : 0.0);
    forward[j] = f;
  }
  double quadratic = 0.0, b = 0.0;
  for (size_t j = n; j-- > 0;) {
    b = w[j] + (j + 1 < n ? std::exp(-(t_s[j + 1] - t_s[j]) / drift.tau_s) * b : 0.0);
    quadratic += w[j] * (forward[j] + b - w[j]);
  }
  return drift.sigma * drift.sigma * quadratic + white * mean_variance;
}

TransientFit FitTransients(const IntervalMeans& means, int axis, double tau_s, std::optional<double> end_tau_s) {
  const int p = end_tau_s.has_value() ? 3 : 2;
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  double syy = 0.0;
  const double end_s = means.t_s.empty() ? 0.0 : means.t_s.back();
  for (size_t j = 0; j < means.t_s.size(); ++j) {
    const Eigen::Vector3d x(1.0, std::exp(-means.t_s[j] / tau_s),
                            end_tau_s.has_value() ? std::exp(-(end_s - means.t_s[j]) / *end_tau_s) : 0.0);
    const double y = means.mean[j][axis];
    normal.noalias() += x * x.transpose();
    rhs += x * y;
    syy += y * y;
  }
  TransientFit fit;
  const auto block = normal.topLeftCorner(p, p);
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(block);
  if (!lu.isInvertible()) return fit;
  const Eigen::MatrixXd inverse = lu.inverse();
  const Eigen::VectorXd beta = inverse * rhs.head(p);
  fit.b = beta[1];
  if (p == 3) fit.b_end = beta[2];
  fit.rss = syy - beta.dot(rhs.head(p));
  return fit;
}

// The weights of b and b′ in the fit at (τ, τ′): rows of (XᵀX)⁻¹Xᵀ.
void WeighTheFit(const IntervalMeans& means, double tau_s, std::optional<double> end_tau_s, TransientFit& fit) {
  const int p = end_tau_s.has_value() ? 3 : 2;
  const double end_s = means.t_s.empty() ? 0.0 : means.t_s.back();
  const auto regressors = [&](size_t j) {
    return Eigen::Vector3d(1.0, std::exp(-means.t_s[j] / tau_s),
                           end_tau_s.has_value() ? std::exp(-(end_s - means.t_s[j]) / *end_tau_s) : 0.0);
  };
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  for (size_t j = 0; j < means.t_s.size(); ++j) normal.noalias() += regressors(j) * regressors(j).transpose();
  const Eigen::MatrixXd inverse = Eigen::MatrixXd(normal.topLeftCorner(p, p)).inverse();
  fit.b_weights.resize(means.t_s.size());
  fit.b_end_weights.assign(p == 3 ? means.t_s.size() : 0, 0.0);
  for (size_t j = 0; j < means.t_s.size(); ++j) {
    const Eigen::VectorXd row = inverse * regressors(j).head(p);
    fit.b_weights[j] = row[1];
    if (p == 3) fit.b_end_weights[j] = row[2];
  }
}

const EffectFamily* TurnOnFamily(int axis) {
  return FindEffectFamily(axis < 3 ? "gyro_turn_on_bias" : "acc_turn_on_bias");
}

std::string WarmUpName(int axis) {
  std::string name = axis < 3 ? "gyro_warm_up." : "acc_warm_up.";
  name.push_back(static_cast<char>('x' + axis % 3));
  return name;
}

}  // namespace

std::vector<WarmUp> FitWarmUps(const BenchRun& run, const ErrorModel& a_priori, double update_interval_s,
                               double still_tolerance_rad, std::optional<double> bench_moved_from_s,
                               const WarmUpOptions& options) {
  std::vector<WarmUp> out;
  if (run.samples.size() < 3 || !(update_interval_s > 0.0)) return out;
  const IntervalMeans means =
      MeansOverTheQuietStillStart(run, update_interval_s, still_tolerance_rad, bench_moved_from_s);
  if (means.t_s.empty()) return out;
  const double span_s = means.t_s.back() + 0.5 * update_interval_s;
  const double shortest_s = options.shortest_intervals * update_interval_s;
  const double longest_s = options.longest_share * span_s;
  if (!(longest_s > shortest_s)) return out;
  std::vector<double> grid_s;
  const double step = std::pow(10.0, 1.0 / options.grid_per_decade);
  for (double tau = shortest_s; tau <= longest_s; tau *= step) grid_s.push_back(tau);

  const double threshold = stats::ChiSquareQuantile(1.0 - options.family_wise_alpha / kSensorAxisCount, 1.0);
  for (int axis = 0; axis < kSensorAxisCount; ++axis) {
    const SensorTriadModel& triad = axis < 3 ? a_priori.gyro : a_priori.acc;
    const double density = triad.white_noise_density[axis % 3];
    // The best transient at the start; then, beside it, the best one ending
    // at the still start's end.
    WarmUp best;
    best.axis = axis;
    TransientFit start_fit;
    for (double tau_s : grid_s) {
      const TransientFit fit = FitTransients(means, axis, tau_s, std::nullopt);
      if (fit.rss < start_fit.rss) {
        start_fit = fit;
        best.tau_s = tau_s;
      }
    }
    if (!(best.tau_s > 0.0)) continue;
    TransientFit both;
    double both_end_tau_s = 0.0;
    for (double end_tau_s : grid_s) {
      const TransientFit fit = FitTransients(means, axis, best.tau_s, end_tau_s);
      if (fit.rss < both.rss) {
        both = fit;
        both_end_tau_s = end_tau_s;
      }
    }
    // Each amplitude against its spread under the stationary model: the
    // white noise of the interval means, N²/Δ, and the a-priori drift.
    const double mean_variance = density * density / update_interval_s;
    const GaussMarkov& drift = triad.bias[static_cast<size_t>(axis % 3)];
    WeighTheFit(means, best.tau_s, std::nullopt, start_fit);
    best.amplitude = start_fit.b;
    best.std_error = std::sqrt(VarianceUnderStationaryDrift(start_fit.b_weights, means.t_s, GaussMarkov{}, mean_variance));
    best.statistic =
        best.amplitude * best.amplitude / VarianceUnderStationaryDrift(start_fit.b_weights, means.t_s, drift, mean_variance);
    if (both_end_tau_s > 0.0) {
      WeighTheFit(means, best.tau_s, both_end_tau_s, both);
      best.end_statistic =
          both.b_end * both.b_end / VarianceUnderStationaryDrift(both.b_end_weights, means.t_s, drift, mean_variance);
    }
    best.significant = best.statistic > threshold && !(best.end_statistic > threshold);
    out.push_back(best);
  }
  return out;
}

std::vector<ParameterEstimate> RemoveWarmUps(BenchRun& run, const ErrorModel& a_priori, double update_interval_s,
                                             double still_tolerance_rad, std::optional<double> bench_moved_from_s,
                                             const WarmUpOptions& options, std::vector<std::string>& notes) {
  std::vector<ParameterEstimate> removed;
  std::string list;
  const double t0_s = run.samples.empty() ? 0.0 : run.samples.front().t_s;
  for (const WarmUp& w :
       FitWarmUps(run, a_priori, update_interval_s, still_tolerance_rad, bench_moved_from_s, options)) {
    if (!w.significant) continue;
    for (ImuSample& s : run.samples) {
      // The interval's mean of b e^{−t/τ} over (t − Δt, t] is within a
      // fraction Δt/τ of its value at the interval's middle; τ ≥ 3 updates.
      const double b = w.amplitude * std::exp(-(s.t_s - t0_s) / w.tau_s);
      (w.axis < 3 ? s.gyro_rad_s : s.acc_mps2)[w.axis % 3] -= b;
    }
    const std::string unit(TurnOnFamily(w.axis)->unit);
    ParameterEstimate amplitude;
    amplitude.name = WarmUpName(w.axis);
    amplitude.value = w.amplitude;
    amplitude.std_error = w.std_error;
    amplitude.method = EstimationMethod::kStaticMeans;
    amplitude.unit = unit;
    amplitude.a_priori = 0.0;
    ParameterEstimate tau;
    tau.name = absl::StrCat(amplitude.name, ".tau");
    tau.value = w.tau_s;
    tau.method = EstimationMethod::kStaticMeans;
    tau.unit.assign(1, 's');  // seconds (assigning the one-letter literal trips GCC 12's -Wrestrict)
    removed.push_back(std::move(amplitude));
    removed.push_back(std::move(tau));
    absl::StrAppend(&list, list.empty() ? "" : ", ",
                    absl::StrFormat("%s %.3g ± %.2g %s settling with τ %.3g s (%.0f a-priori drift σ)",
                                    WarmUpName(w.axis), w.amplitude, w.std_error, unit, w.tau_s,
                                    std::sqrt(w.statistic)));
  }
  if (!list.empty()) {
    notes.push_back(absl::StrCat(
        "biases settling after power-up (warm-up), fitted as b·e^(−t/τ) on the run's still start, beyond what a "
        "stationary drift starts with at the family-wise level, and removed from the samples before "
        "identification: ",
        list));
  }
  return removed;
}

}  // namespace insdiag::engine::ident
