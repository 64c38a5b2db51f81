#include "insdiag/engine/monitor/innovation_tests.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine {
namespace {

// The (1 − p) quantile of χ²_ν/ν, for the effective ν of a window.
double GradualThreshold(double p, double effective_dof) {
  return stats::ChiSquareQuantile(1.0 - p, effective_dof) / effective_dof;
}

// How many tests a window of W updates moved over K updates counts as, for a
// family-wise level `alpha` of its maximum. Neighbouring windows overlap, so
// there are fewer than K − W + 1 tests, but far more than the K/W disjoint
// ones: the standardised moving sum has correlation 1 − |d|/W at lag d, and
// for such a process P(max > u) ≈ (K/W)·u²·(1 − Φ(u)) (Pickands, Trans. AMS
// 145, 1969; Leadbetter, Lindgren & Rootzén, Extremes, 1983, §12.2). The
// count (K/W)·u², with u the per-test level's normal quantile, is solved by
// fixed point. Checked by simulation of χ²₁ sequences (K 600–20000, W
// 10–100): family-wise rate 0.3–0.6 α where K/W disjoint windows gave 5–9 α.
double ScanTestCount(int K, int W, double alpha) {
  const double disjoint = std::max(1.0, static_cast<double>(K) / W);
  const double positions = std::max(1.0, static_cast<double>(K - W + 1));
  double count = disjoint;
  for (int i = 0; i < 20; ++i) {
    const double u = stats::NormalQuantile(1.0 - alpha / count);
    count = std::clamp(disjoint * u * u, disjoint, positions);
  }
  return count;
}

}  // namespace

InnovationTests::InnovationTests(int planned_epochs, double epoch_interval_s, const MonitorOptions& options)
    : epoch_interval_s_(epoch_interval_s) {
  const int K = std::max(planned_epochs, 1);
  // The verdict rests on three families of tests (outliers, gradual failures,
  // the mean NIS); Bonferroni's split keeps a healthy unit GOOD with
  // probability ≥ 1 − family_wise_alpha.
  const double alpha = options.family_wise_alpha / 3.0;
  gamma2_ = 1.0 + 3.0 * std::numbers::sqrt2;
  window_ = std::clamp(static_cast<int>(std::lround(options.window_s / epoch_interval_s)), 2, std::max(2, K));
  eta2_ = 1.0 + 3.0 * std::sqrt(2.0 / window_);  // a + 3√(2b), a = 1, b = 1/W
  // Family-wise thresholds (Bonferroni over the run's updates, or over the
  // tests the moving window amounts to).
  outlier_threshold_ = stats::ChiSquareQuantile(1.0 - alpha / (kChannelCount * K), 1.0);
  window_alpha_ = alpha / (kChannelCount * ScanTestCount(K, window_, alpha / kChannelCount));
  gradual_threshold_ = stats::ChiSquareQuantile(1.0 - window_alpha_, window_) / window_;
  window_nu2_.resize(static_cast<size_t>(window_));
  window_S_.resize(static_cast<size_t>(window_));
  window_start_s_.resize(static_cast<size_t>(window_));
  window_ratio_.fill(std::numeric_limits<double>::quiet_NaN());
  faults_.reserve(64);
}

void InnovationTests::AddInterval(int channel, double start_s, double end_s, FaultKind kind, double statistic) {
  // Intervals an update apart are one.
  AddFaultInterval(faults_, kChannelNames[static_cast<size_t>(channel)], start_s, end_s, kind, statistic,
                   epoch_interval_s_);
  if (kind == FaultKind::kGradual) gradual_found_ = true;
}

void InnovationTests::Add(double start_s, double time_s, const PerChannel& innovation, const PerChannel& innovation_variance,
                          bool reference_holds) {
  const int k = epochs_++;
  const auto slot = static_cast<size_t>(k % window_);
  window_start_s_[slot] = start_s;
  // Where the window's first epoch (k − W + 1) starts, once the window is full.
  const double window_start_s = window_start_s_[static_cast<size_t>((k + 1) % window_)];
  for (int c = 0; c < kChannelCount; ++c) {
    const auto ch = static_cast<size_t>(c);
    const double nu = innovation[ch];
    const double S = innovation_variance[ch];
    const bool observed = S > 0.0;  // else ν = S = 0 (ForwardPass::Observed)
    beta2_[ch] = observed ? nu * nu / S : std::numeric_limits<double>::quiet_NaN();
    if (observed) {
      ++observed_[ch];
      if (beta2_[ch] > gamma2_) ++over_gamma2_[ch];
    }
    // Where the bench moved, the update tests the bench: it is neither an
    // outlier of the unit nor part of a window's evidence.
    const bool tested = observed && reference_holds;
    if (tested) {
      ++window_observed_[ch];
      if (beta2_[ch] > outlier_threshold_) AddInterval(c, start_s, time_s, FaultKind::kOutlier, beta2_[ch]);
    }
    const double nu2 = tested ? nu * nu : 0.0;
    const double S_tested = tested ? S : 0.0;
    sum_nu2_[ch] += nu2;
    sum_S_[ch] += S_tested;
    sum_S2_[ch] += S_tested * S_tested;
    if (k >= window_) {
      const double nu2_old = window_nu2_[slot][ch];
      const double S_old = window_S_[slot][ch];
      if (S_old > 0.0) --window_observed_[ch];
      sum_nu2_[ch] -= nu2_old;
      sum_S_[ch] -= S_old;
      sum_S2_[ch] -= S_old * S_old;
    }
    window_nu2_[slot][ch] = nu2;
    window_S_[slot][ch] = S_tested;
    if (window_observed_[ch] == 0) {
      // Exactly nothing, not the rounding the moving sums leave behind.
      sum_nu2_[ch] = sum_S_[ch] = sum_S2_[ch] = 0.0;
    }
    if (k < window_ - 1) continue;
    if (window_observed_[ch] == 0) {
      window_ratio_[ch] = std::numeric_limits<double>::quiet_NaN();
      continue;
    }
    ++windows_[ch];
    const double F = sum_nu2_[ch] / sum_S_[ch];
    window_ratio_[ch] = F;
    if (F > eta2_) ++over_eta2_[ch];
    // F = Σν²/ΣS weighs each β² by its S: where S changes within the
    // window (the filter's start-up) or the channel is observed at some of
    // its epochs only, it is a weighted sum of χ²₁ with ν = (ΣS)²/ΣS² ≤ W
    // effective degrees of freedom (Satterthwaite, Biometrics Bull. 2(6),
    // 1946), and its quantile is higher than χ²_W/W's; checked only past
    // the cheaper W-dof threshold.
    if (F > gradual_threshold_ &&
        F > GradualThreshold(window_alpha_, sum_S_[ch] * sum_S_[ch] / sum_S2_[ch])) {
      AddInterval(c, window_start_s, time_s, FaultKind::kGradual, F);
    }
  }
}

}  // namespace insdiag::engine
