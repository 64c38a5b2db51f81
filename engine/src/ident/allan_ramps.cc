// Ramps in a static segment's rate (allan.h: Ramps).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <random>
#include <span>
#include <vector>

#include "allan_model.h"
#include "insdiag/engine/ident/allan.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine::ident {
namespace {

using namespace allan_model;  // the phase, shared with the curve

// σ̂² and σ̂²_H at cluster size m, pooled over the pieces' phases θ (each
// difference of the one a piece's; a piece too short for 3m adds to neither).
struct VariancePair {
  double avar = 0.0;
  double hvar = 0.0;
};
VariancePair PooledVariances(std::span<const std::vector<double>> phases, int64_t m) {
  double sum_a = 0.0;
  double sum_h = 0.0;
  int64_t count_a = 0;
  int64_t count_h = 0;
  for (const std::vector<double>& th : phases) {
    const auto n = static_cast<int64_t>(th.size());
    if (n - 3 * m < 1) continue;
    const auto at = [&](int64_t i) { return th[static_cast<size_t>(i)]; };
    for (int64_t k = 0; k + 2 * m < n; ++k) {
      const double a = at(k + 2 * m) - 2.0 * at(k + m) + at(k);
      sum_a += a * a;
    }
    for (int64_t k = 0; k + 3 * m < n; ++k) {
      const double h = at(k + 3 * m) - 3.0 * at(k + 2 * m) + 3.0 * at(k + m) - at(k);
      sum_h += h * h;
    }
    count_a += n - 2 * m;
    count_h += n - 3 * m;
  }
  const auto dm = static_cast<double>(m);
  if (count_h < 1) return {};
  return {sum_a / (2.0 * dm * dm * static_cast<double>(count_a)),
          sum_h / (6.0 * dm * dm * static_cast<double>(count_h))};
}

// The tested cluster sizes: the curve's that hold from kFewestWindowsTested
// to kMostWindowsTested windows of the longest piece: where a ramp shows (its
// share of σ² grows as τ²), short of the longest τ, where the ratio of two
// estimates of few degrees of freedom has tails no normal law describes.
constexpr int64_t kMostWindowsTested = 64;
constexpr int64_t kFewestWindowsTested = 8;
// The null is simulated at this many steps to the smallest tested m.
constexpr int64_t kNullStepsPerCluster = 8;
constexpr size_t kNullReplicates = 2000;
constexpr uint64_t kNullSeed = 0x5eedf00d;

// The null: a rate random walk alone, the model's noise of the largest
// σ²/σ²_H (allan.h: Ramps). A walk is self-similar, so ln(σ̂²/σ̂²_H) at each
// tested m depends only on the pieces' lengths in units of m, and a walk of
// g-sample steps stands for the segment's samples. The test's statistic is
// the largest of the standardised ln ratios over the tested m; its bound at
// level α is the upper tail of that maximum over the replicates, exponential
// beyond their 95th percentile (peaks over a threshold: the maximum of ln
// ratios of χ² variates is in the Gumbel domain, whose excesses are
// exponential; Pickands, Ann. Stat. 3(1), 1975).
struct RandomWalkNull {
  std::vector<double> mean;  // of ln(σ̂²/σ̂²_H) at each tested m
  std::vector<double> sd;
  double bound = 0.0;  // of the largest standardised ln ratio, at level α
  // The tail: P(max > z) = (1 − q) e^{−(z − threshold)/mean_excess} beyond
  // the replicates' q-quantile `threshold`.
  double threshold = 0.0;
  double mean_excess = 0.0;

  // P(max > z) under the walk; for z within the replicates' bulk, the tail's
  // share at its threshold (a bound: such z are never a ramp).
  double PValue(double z) const;
};
constexpr double kTailThresholdQuantile = 0.95;

RandomWalkNull NullOfRandomWalk(std::span<const size_t> piece_samples,
                                std::span<const int64_t> tested_m, double alpha) {
  const int64_t step = std::max<int64_t>(1, tested_m.front() / kNullStepsPerCluster);
  std::vector<int64_t> coarse_m;
  for (int64_t m : tested_m) coarse_m.push_back(std::max<int64_t>(1, (m + step / 2) / step));
  std::mt19937_64 rng(kNullSeed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const size_t points = tested_m.size();
  std::vector<double> log_ratio(kNullReplicates * points, 0.0);  // replicate-major
  std::vector<std::vector<double>> walks(piece_samples.size());
  std::vector<std::vector<double>> phases(piece_samples.size());
  for (size_t r = 0; r < kNullReplicates; ++r) {
    for (size_t i = 0; i < piece_samples.size(); ++i) {
      walks[i].resize(static_cast<size_t>(static_cast<int64_t>(piece_samples[i]) / step));
      double level = 0.0;
      for (double& v : walks[i]) v = level += normal(rng);
      PhaseOfRates(walks[i], phases[i]);
    }
    for (size_t j = 0; j < points; ++j) {
      const VariancePair v = PooledVariances(phases, coarse_m[j]);
      log_ratio[r * points + j] = v.hvar > 0.0 ? std::log(v.avar / v.hvar) : 0.0;
    }
  }
  RandomWalkNull null;
  for (size_t j = 0; j < points; ++j) {
    double sum = 0.0;
    double sum_squares = 0.0;
    for (size_t r = 0; r < kNullReplicates; ++r) {
      sum += log_ratio[r * points + j];
      sum_squares += log_ratio[r * points + j] * log_ratio[r * points + j];
    }
    const double mean = sum / kNullReplicates;
    null.mean.push_back(mean);
    null.sd.push_back(std::sqrt(std::max(0.0, sum_squares / kNullReplicates - mean * mean)));
  }
  std::vector<double> largest(kNullReplicates, -std::numeric_limits<double>::infinity());
  for (size_t r = 0; r < kNullReplicates; ++r) {
    for (size_t j = 0; j < points; ++j) {
      if (null.sd[j] > 0.0)
        largest[r] = std::max(largest[r], (log_ratio[r * points + j] - null.mean[j]) / null.sd[j]);
    }
  }
  std::ranges::sort(largest);
  const auto threshold_index = static_cast<size_t>(kTailThresholdQuantile * kNullReplicates);
  const double threshold = largest[threshold_index];
  double excess = 0.0;
  for (size_t r = threshold_index + 1; r < kNullReplicates; ++r) excess += largest[r] - threshold;
  excess /= static_cast<double>(kNullReplicates - threshold_index - 1);
  null.bound = threshold + excess * std::log((1.0 - kTailThresholdQuantile) / alpha);
  null.threshold = threshold;
  null.mean_excess = excess;
  return null;
}

double RandomWalkNull::PValue(double z) const {
  if (!(mean_excess > 0.0) || z <= threshold) return 1.0 - kTailThresholdQuantile;
  return (1.0 - kTailThresholdQuantile) * std::exp(-(z - threshold) / mean_excess);
}

// The null is a function of the pieces' lengths, the tested m and α alone,
// and a run's six channels share their static segments: each thread keeps
// the last one it simulated.
const RandomWalkNull& CachedNullOfRandomWalk(const std::vector<size_t>& piece_samples,
                                             const std::vector<int64_t>& tested_m, double alpha) {
  struct Memo {
    std::vector<size_t> piece_samples;
    std::vector<int64_t> tested_m;
    double alpha = 0.0;
    RandomWalkNull null;
  };
  thread_local std::optional<Memo> memo;
  if (!memo.has_value() || memo->piece_samples != piece_samples || memo->tested_m != tested_m ||
      memo->alpha != alpha) {
    memo = Memo{piece_samples, tested_m, alpha, NullOfRandomWalk(piece_samples, tested_m, alpha)};
  }
  return memo->null;
}

}  // namespace

std::optional<RampEvidence> RampBeyondNoise(std::span<const std::vector<double>> segment_rates,
                                            std::span<const AllanPoint> curve,
                                            const AllanOptions& options) {
  if (!(options.ramp_alpha > 0.0) || segment_rates.empty()) return std::nullopt;
  std::vector<size_t> piece_samples;
  std::vector<std::vector<double>> phases;
  int64_t longest = 0;
  for (const std::vector<double>& y : segment_rates) {
    piece_samples.push_back(y.size());
    phases.push_back(PhaseOfRates(y));
    longest = std::max(longest, static_cast<int64_t>(y.size()));
  }
  std::vector<int64_t> tested_m;
  std::vector<double> tested_tau_s;
  std::vector<VariancePair> measured;
  for (const AllanPoint& p : curve) {
    if (p.m * kMostWindowsTested < longest || p.m * kFewestWindowsTested > longest) continue;
    const VariancePair v = PooledVariances(phases, p.m);
    if (!(v.hvar > 0.0) || !(v.avar > 0.0)) continue;
    tested_m.push_back(p.m);
    tested_tau_s.push_back(p.tau_s);
    measured.push_back(v);
  }
  if (tested_m.empty()) return std::nullopt;
  const RandomWalkNull& null = CachedNullOfRandomWalk(piece_samples, tested_m, options.ramp_alpha);
  std::optional<RampEvidence> best;
  for (size_t j = 0; j < tested_m.size(); ++j) {
    if (!(null.sd[j] > 0.0)) continue;
    const double ratio = measured[j].avar / measured[j].hvar;
    const double z = (std::log(ratio) - null.mean[j]) / null.sd[j];
    if (!best.has_value() || z > best->z)
      best = RampEvidence{tested_tau_s[j], ratio, z, null.PValue(z)};
  }
  if (!best.has_value() || best->z <= null.bound) return std::nullopt;
  return best;
}

std::optional<RateRamp> FitRateRamp(std::span<const double> rates, double tau0_s,
                                    size_t min_samples_after) {
  const size_t n = rates.size();
  if (n < min_samples_after + 1) return std::nullopt;
  double mean = 0.0;
  for (double v : rates) mean += v;
  mean /= static_cast<double>(n);
  // With u_k = (k − j)₊ for an onset at sample j and y mean-free, the fit's
  // reduction of the squared residual is S_uy² / S_uu, where
  //   S_uy = Σ_{k>j} k y_k − j Σ_{k>j} y_k,   S_uu = Σ u² − (Σ u)² / n,
  //   Σ u = L(L+1)/2, Σ u² = L(L+1)(2L+1)/6, L = n − 1 − j;
  // suffix sums give every onset in one sweep from the end.
  const auto dn = static_cast<double>(n);
  double suffix_y = 0.0;
  double suffix_ky = 0.0;
  std::optional<RateRamp> best;
  for (size_t j = n - 1; j-- > 0;) {
    const double y = rates[j + 1] - mean;
    suffix_y += y;
    suffix_ky += static_cast<double>(j + 1) * y;
    const size_t after = n - 1 - j;
    if (after < min_samples_after) continue;
    const auto L = static_cast<double>(after);
    const double sum_u = 0.5 * L * (L + 1.0);
    const double sum_uu = L * (L + 1.0) * (2.0 * L + 1.0) / 6.0;
    const double s_uu = sum_uu - sum_u * sum_u / dn;
    const double s_uy = suffix_ky - static_cast<double>(j) * suffix_y;
    if (!(s_uu > 0.0)) continue;
    const double reduction = s_uy * s_uy / s_uu;
    if (!best.has_value() || reduction > best->residual_reduction) {
      best = RateRamp{.onset_sample = j,
                      .onset_s = static_cast<double>(j) * tau0_s,
                      .slope = s_uy / s_uu / tau0_s,
                      .residual_reduction = reduction};
    }
  }
  return best;
}

}  // namespace insdiag::engine::ident
