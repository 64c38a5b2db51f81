#include "insdiag/engine/monitor/monitoring.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "insdiag/engine/filter/linear_range.h"
#include "insdiag/engine/monitor/innovation_tests.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine {
void AddFaultInterval(std::vector<FaultInterval>& faults, std::string_view channel, double start_s, double end_s,
                      FaultKind kind, double statistic, double join_gap_s) {
  for (auto it = faults.rbegin(); it != faults.rend(); ++it) {
    if (it->channel != channel || it->kind != kind) continue;
    if (start_s <= it->end_s + join_gap_s) {
      it->end_s = std::max(it->end_s, end_s);
      it->peak_statistic = std::max(it->peak_statistic, statistic);
      return;
    }
    break;
  }
  faults.push_back({std::string(channel), start_s, end_s, kind, statistic});
}

void SortFaultIntervals(std::vector<FaultInterval>& faults) {
  std::stable_sort(faults.begin(), faults.end(),
                   [](const FaultInterval& a, const FaultInterval& b) { return a.start_s < b.start_s; });
}

MeanNisBand MeanNisBandOf(int updates, double family_wise_alpha) {
  if (updates <= 0) return {0.0, 0.0};
  // The NIS is one of the verdict's three families of tests (InnovationTests).
  const double alpha = family_wise_alpha / 3.0;
  // Mean of `updates` χ²(1) values: N·mean ~ χ²(N).
  return {stats::ChiSquareQuantile(alpha / 2.0, updates) / updates,
          stats::ChiSquareQuantile(1.0 - alpha / 2.0, updates) / updates};
}

Verdict VerdictOf(bool gradual_failure, bool any_interval, bool nis_outside_band) {
  if (gradual_failure) return Verdict::kFaulty;
  if (any_interval || nis_outside_band) return Verdict::kOperable;
  return Verdict::kGood;
}

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

MonitorResult Monitor(const ForwardPass& fw, const SmoothedPass& sm, const StateLayout& layout,
                      const SampleScreening& samples, const MonitorOptions& options) {
  MonitorResult out;
  const int K = fw.epochs();
  const double epoch_interval = K > 1 ? (fw.epoch_time_s.back() - fw.epoch_time_s.front()) / (K - 1) : 1.0;
  InnovationTests tests(K, epoch_interval, options);
  out.gamma2 = tests.gamma2();
  out.eta2 = tests.eta2();
  out.window_updates = tests.window_updates();
  out.window_ratio.resize(K, kChannelCount);
  InnovationTests::PerChannel nu, S;
  for (int k = 0; k < K; ++k) {
    for (int c = 0; c < kChannelCount; ++c) {
      nu[static_cast<size_t>(c)] = fw.innovation(k, c);
      S[static_cast<size_t>(c)] = fw.innovation_variance(k, c);
    }
    const double start_s = fw.epoch_start_s[static_cast<size_t>(k)];
    const double end_s = fw.epoch_time_s[static_cast<size_t>(k)];
    tests.Add(start_s, end_s, nu, S, !BenchMovedWithin(samples.bench_motion, start_s, end_s));
    for (int c = 0; c < kChannelCount; ++c) out.window_ratio(k, c) = tests.window_ratio()[static_cast<size_t>(c)];
  }
  out.faults = tests.faults();

  std::vector<double> normalised;
  normalised.reserve(static_cast<size_t>(K));
  double nis_total = 0.0;
  for (int c = 0; c < kChannelCount; ++c) {
    ChannelFit fit;
    fit.name = std::string(kChannelNames[static_cast<size_t>(c)]);
    fit.unit = std::string(kChannelUnits[static_cast<size_t>(c)]);
    // Over the epochs the channel was observed at (all of them but the
    // attitude's while the table turns).
    int observed = 0;
    double nu2 = 0.0, nis = 0.0, z_mean = 0.0;
    for (int k = 0; k < K; ++k) {
      if (!fw.Observed(k, c)) continue;
      z_mean += fw.z(k, c);
      ++observed;
    }
    fit.count = observed;
    if (observed > 0) z_mean /= observed;
    double z_spread = 0.0;
    normalised.clear();
    for (int k = 0; k < K; ++k) {
      if (!fw.Observed(k, c)) continue;
      const double innovation = fw.innovation(k, c);
      const double variance = fw.innovation_variance(k, c);
      nu2 += innovation * innovation;
      nis += innovation * innovation / variance;
      z_spread += (fw.z(k, c) - z_mean) * (fw.z(k, c) - z_mean);
      normalised.push_back(innovation / std::sqrt(variance));
    }
    fit.rms = observed > 0 ? std::sqrt(nu2 / observed) : 0.0;
    fit.fit_percent = z_spread > 0.0 ? 100.0 * (1.0 - std::sqrt(nu2 / z_spread)) : 0.0;
    fit.nis_mean = observed > 0 ? nis / observed : 0.0;
    fit.whiteness_p_value = observed > 0 ? stats::LjungBoxPValue(normalised, std::min(options.whiteness_lags, observed / 5))
                                         : 1.0;
    fit.fraction_over_gamma2 = observed > 0 ? static_cast<double>(tests.over_gamma2(c)) / observed : 0.0;
    fit.fraction_over_eta2 =
        tests.windows(c) > 0 ? static_cast<double>(tests.over_eta2(c)) / tests.windows(c) : 0.0;
    nis_total += nis;
    out.channels.push_back(std::move(fit));
  }
  for (const SampleOutlier& s : samples.spikes) {
    AddFaultInterval(out.faults, kSensorChannelNames[s.sensor_channel], s.time_s, s.time_s, FaultKind::kOutlier,
                     s.robust_z, 0.0);
  }
  SortFaultIntervals(out.faults);

  const int updates = fw.scalar_updates;
  out.nis_mean = updates > 0 ? nis_total / updates : 0.0;
  const MeanNisBand nis_band = MeanNisBandOf(updates, options.family_wise_alpha);
  out.nis_band_low = nis_band.low;
  out.nis_band_high = nis_band.high;

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
    // The likeliest jump the first-order model can describe (fault_localisation.h).
    const auto hypotheses = LocaliseJump(fw, layout, f.start_s, options.localisation);
    const auto h = std::ranges::find_if(hypotheses, [](const JumpHypothesis& j) {
      return LinearRangeOf(j.peak_attitude_error_rad, j.jump_std_error / std::abs(j.jump)) !=
             LinearRange::kFarOutside;
    });
    if (h != hypotheses.end() && h->p_value < options.family_wise_alpha) {
      out.localisation.push_back(
          {h->state, h->onset_s, h->statistic, h->p_value, "JUMP", h->jump, h->jump_std_error});
    }
    localised_until = f.end_s;
  }

  out.verdict = VerdictOf(tests.gradual_found(), !out.faults.empty(), nis_band.Excludes(out.nis_mean));
  return out;
}

}  // namespace insdiag::engine
