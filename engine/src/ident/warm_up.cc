#include "insdiag/engine/ident/warm_up.h"

#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>

#include <algorithm>
#include <cmath>

#include "insdiag/engine/filter/start_departure.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine::ident {
namespace {

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

// Least squares of y = c + b e^{−t/τ} on the interval means of one axis:
// b, its variance per unit variance of a mean, and the residual sum of squares.
struct TransientFit {
  double b = 0.0;
  double b_variance_factor = 0.0;
  double rss = 0.0;
};

TransientFit FitTransient(const IntervalMeans& means, int axis, double tau_s) {
  double n = 0, se = 0, see = 0, sy = 0, sey = 0, syy = 0;
  for (size_t j = 0; j < means.t_s.size(); ++j) {
    const double e = std::exp(-means.t_s[j] / tau_s);
    const double y = means.mean[j][axis];
    n += 1.0;
    se += e;
    see += e * e;
    sy += y;
    sey += e * y;
    syy += y * y;
  }
  const double det = n * see - se * se;
  TransientFit fit;
  if (!(det > 0.0)) return fit;
  const double c = (see * sy - se * sey) / det;
  fit.b = (n * sey - se * sy) / det;
  fit.b_variance_factor = n / det;
  fit.rss = syy - c * sy - fit.b * sey;
  return fit;
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
    const double sigma = triad.bias[static_cast<size_t>(axis % 3)].sigma;
    WarmUp best;
    best.axis = axis;
    double best_rss = std::numeric_limits<double>::infinity();
    for (double tau_s : grid_s) {
      const TransientFit fit = FitTransient(means, axis, tau_s);
      if (fit.b_variance_factor > 0.0 && fit.rss < best_rss) {
        best_rss = fit.rss;
        best.amplitude = fit.b;
        best.tau_s = tau_s;
        // The white noise of one interval's mean, N²/Δ.
        best.std_error = std::sqrt(fit.b_variance_factor * density * density / update_interval_s);
      }
    }
    if (!(best.tau_s > 0.0)) continue;
    best.statistic = best.amplitude * best.amplitude / (sigma * sigma + best.std_error * best.std_error);
    best.significant = best.statistic > threshold;
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
