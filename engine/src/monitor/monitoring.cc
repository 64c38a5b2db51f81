#include "insdiag/engine/monitor/monitoring.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine {
namespace {

// Appends [start, end] to `faults`, merging with the previous interval of the
// same channel and kind when they touch.
void AddInterval(std::vector<FaultInterval>& faults, const std::string& channel, double start, double end,
                 FaultKind kind, double statistic, double join_gap) {
  for (auto it = faults.rbegin(); it != faults.rend(); ++it) {
    if (it->channel != channel || it->kind != kind) continue;
    if (start <= it->end_s + join_gap) {
      it->end_s = std::max(it->end_s, end);
      it->peak_statistic = std::max(it->peak_statistic, statistic);
      return;
    }
    break;
  }
  faults.push_back({channel, start, end, kind, statistic});
}

}  // namespace

const char* VerdictName(Verdict v) {
  switch (v) {
    case Verdict::kGood:
      return "GOOD";
    case Verdict::kOperable:
      return "OPERABLE";
    case Verdict::kFaulty:
      return "FAULTY";
  }
  return "";
}

const char* FaultKindName(FaultKind k) {
  switch (k) {
    case FaultKind::kOutlier:
      return "OUTLIER";
    case FaultKind::kGradual:
      return "GRADUAL";
    case FaultKind::kAbrupt:
      return "ABRUPT";
  }
  return "GRADUAL";
}

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

MonitorResult Monitor(const ForwardPass& fw, const SmoothedPass& sm, const StateLayout& layout,
                      const std::vector<SampleOutlier>& spikes, const MonitorOptions& options) {
  MonitorResult out;
  const int K = fw.epochs();
  // The verdict rests on three families of tests (outliers, gradual failures,
  // the mean NIS); Bonferroni's split keeps a healthy unit GOOD with
  // probability ≥ 1 − family_wise_alpha.
  const double alpha = options.family_wise_alpha / 3.0;
  out.gamma2 = 1.0 + 3.0 * std::numbers::sqrt2;
  const double epoch_interval = K > 1 ? (fw.epoch_time_s.back() - fw.epoch_time_s.front()) / (K - 1) : 1.0;
  const int W = std::clamp(static_cast<int>(std::lround(options.window_s / epoch_interval)), 2, std::max(2, K));
  out.window_updates = W;
  out.eta2 = 1.0 + 3.0 * std::sqrt(2.0 / W);  // a + 3√(2b), a = 1, b = 1/W
  // Family-wise thresholds (Bonferroni over the run's updates, or over the
  // tests the moving window amounts to).
  const double outlier_threshold = stats::ChiSquareQuantile(1.0 - alpha / (kChannelCount * std::max(K, 1)), 1.0);
  const double window_alpha = alpha / (kChannelCount * ScanTestCount(K, W, alpha / kChannelCount));
  const double gradual_threshold = stats::ChiSquareQuantile(1.0 - window_alpha, W) / W;

  out.window_ratio = Eigen::MatrixXd::Constant(K, kChannelCount, std::numeric_limits<double>::quiet_NaN());
  std::vector<double> normalised(static_cast<size_t>(K));
  double nis_total = 0.0;
  for (int c = 0; c < kChannelCount; ++c) {
    ChannelFit fit;
    fit.name = std::string(kChannelNames[static_cast<size_t>(c)]);
    fit.unit = std::string(kChannelUnits[static_cast<size_t>(c)]);
    fit.count = K;
    double nu2 = 0.0, nis = 0.0, z_mean = 0.0;
    int over_gamma = 0, windows = 0, over_eta = 0;
    double window_nu2 = 0.0, window_s = 0.0, window_s2 = 0.0;
    for (int k = 0; k < K; ++k) z_mean += fw.z(k, c) / K;
    double z_spread = 0.0;
    for (int k = 0; k < K; ++k) {
      const double nu = fw.innovation(k, c);
      const double S = fw.innovation_variance(k, c);
      const double beta2 = nu * nu / S;
      nu2 += nu * nu;
      nis += beta2;
      z_spread += (fw.z(k, c) - z_mean) * (fw.z(k, c) - z_mean);
      normalised[static_cast<size_t>(k)] = nu / std::sqrt(S);
      if (beta2 > out.gamma2) ++over_gamma;
      const double t_prev = k > 0 ? fw.epoch_time_s[static_cast<size_t>(k - 1)] : fw.epoch_time_s[0] - epoch_interval;
      if (beta2 > outlier_threshold) {
        AddInterval(out.faults, fit.name, t_prev, fw.epoch_time_s[static_cast<size_t>(k)], FaultKind::kOutlier, beta2,
                    epoch_interval);
      }
      window_nu2 += nu * nu;
      window_s += S;
      window_s2 += S * S;
      if (k >= W) {
        const double S_old = fw.innovation_variance(k - W, c);
        window_nu2 -= fw.innovation(k - W, c) * fw.innovation(k - W, c);
        window_s -= S_old;
        window_s2 -= S_old * S_old;
      }
      if (k >= W - 1) {
        const double F = window_nu2 / window_s;
        out.window_ratio(k, c) = F;
        ++windows;
        if (F > out.eta2) ++over_eta;
        // F = Σν²/ΣS weighs each β² by its S: where S changes within the
        // window (the filter's start-up) it is a weighted sum of χ²₁ with
        // ν = (ΣS)²/ΣS² ≤ W effective degrees of freedom (Satterthwaite,
        // Biometrics Bull. 2(6), 1946), and its quantile is higher than
        // χ²_W/W's; checked only past the cheaper W-dof threshold.
        if (F > gradual_threshold &&
            F > GradualThreshold(window_alpha, window_s * window_s / window_s2)) {
          AddInterval(out.faults, fit.name, fw.epoch_time_s[static_cast<size_t>(k - W + 1)] - epoch_interval,
                      fw.epoch_time_s[static_cast<size_t>(k)], FaultKind::kGradual, F, epoch_interval);
        }
      }
    }
    fit.rms = K > 0 ? std::sqrt(nu2 / K) : 0.0;
    fit.fit_percent = z_spread > 0.0 ? 100.0 * (1.0 - std::sqrt(nu2 / z_spread)) : 0.0;
    fit.nis_mean = K > 0 ? nis / K : 0.0;
    fit.whiteness_p_value = stats::LjungBoxPValue(normalised, std::min(options.whiteness_lags, K / 5));
    fit.fraction_over_gamma2 = K > 0 ? static_cast<double>(over_gamma) / K : 0.0;
    fit.fraction_over_eta2 = windows > 0 ? static_cast<double>(over_eta) / windows : 0.0;
    nis_total += nis;
    out.channels.push_back(std::move(fit));
  }
  for (const SampleOutlier& s : spikes) {
    AddInterval(out.faults, std::string(kSensorChannelNames[s.sensor_channel]), s.time_s, s.time_s,
                FaultKind::kOutlier, s.robust_z, 0.0);
  }
  std::sort(out.faults.begin(), out.faults.end(),
            [](const FaultInterval& a, const FaultInterval& b) { return a.start_s < b.start_s; });

  const int updates = fw.scalar_updates;
  out.nis_mean = updates > 0 ? nis_total / updates : 0.0;
  // Mean of `updates` χ²(1) values: N·mean ~ χ²(N).
  out.nis_band_low = updates > 0 ? stats::ChiSquareQuantile(alpha / 2.0, updates) / updates : 0.0;
  out.nis_band_high = updates > 0 ? stats::ChiSquareQuantile(1.0 - alpha / 2.0, updates) / updates : 0.0;

  // The seed's forward/backward discrepancy: sensor states whose estimates from
  // past and future data disagree beyond chance.
  const double per_test_alpha = options.family_wise_alpha / std::max(1, K * layout.sensor_count());
  for (const SensorState& s : layout.sensor_states()) {
    double peak = 0.0;
    int at = 0;
    for (int k = 0; k < K; ++k) {
      if (sm.discrepancy(k, s.index) > peak) {
        peak = sm.discrepancy(k, s.index);
        at = k;
      }
    }
    const double p_single = stats::ChiSquareSurvival(peak, 1.0);
    if (p_single < per_test_alpha) {
      out.discrepancies.push_back({s.name, fw.epoch_time_s[static_cast<size_t>(at)], peak,
                                   std::min(1.0, p_single * K * layout.sensor_count()), "FORWARD_BACKWARD", 0.0,
                                   0.0});
    }
  }
  std::sort(out.discrepancies.begin(), out.discrepancies.end(),
            [](const Localisation& a, const Localisation& b) { return a.statistic > b.statistic; });

  // Each gradual failure: which sensor state jumped at its onset.
  double localised_until = -std::numeric_limits<double>::infinity();
  for (const FaultInterval& f : out.faults) {
    if (f.kind != FaultKind::kGradual || f.start_s <= localised_until) continue;
    if (static_cast<int>(out.localisation.size()) >= options.max_localised_failures) break;
    const auto hypotheses = LocaliseJump(fw, layout, f.start_s, options.localisation);
    if (!hypotheses.empty() && hypotheses.front().p_value < options.family_wise_alpha) {
      const JumpHypothesis& h = hypotheses.front();
      out.localisation.push_back({h.state, h.onset_s, h.statistic, h.p_value, "JUMP", h.jump, h.jump_std_error});
    }
    localised_until = f.end_s;
  }

  const bool gradual = std::any_of(out.faults.begin(), out.faults.end(),
                                   [](const FaultInterval& f) { return f.kind == FaultKind::kGradual; });
  const bool nis_off = out.nis_mean < out.nis_band_low || out.nis_mean > out.nis_band_high;
  if (gradual) {
    out.verdict = Verdict::kFaulty;
  } else if (!out.faults.empty() || nis_off) {
    out.verdict = Verdict::kOperable;
  } else {
    out.verdict = Verdict::kGood;
  }
  return out;
}

}  // namespace insdiag::engine
