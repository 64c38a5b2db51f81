#include "insdiag/engine/monitor/bench_motion.h"

#include <algorithm>
#include <cmath>

#include "insdiag/engine/monitor/sample_screening.h"
#include "insdiag/engine/stats/distributions.h"
#include "insdiag/engine/stats/robust.h"

namespace insdiag::engine {
namespace {

constexpr int kChannels = 6;

// One update interval's samples: per channel the log of the departures'
// sample variance, and the range of the reference measurement over it.
struct IntervalScatter {
  double start_s = 0.0;
  double end_s = 0.0;
  std::array<double, kChannels> log_variance{};
  std::array<double, kChannels> reference_range{};
};

std::vector<IntervalScatter> ScatterPerInterval(const BenchRun& run,
                                                const std::vector<std::array<double, 6>>& reference,
                                                size_t per_interval) {
  std::vector<IntervalScatter> out;
  const size_t n = run.samples.size();
  out.reserve(n / per_interval + 1);
  // Sample 0 starts the run (its increment precedes it, epoch_run.h).
  for (size_t first = 1; first + per_interval <= n; first += per_interval) {
    IntervalScatter& s = out.emplace_back();
    s.start_s = run.samples[first - 1].t_s;
    s.end_s = run.samples[first + per_interval - 1].t_s;
    for (int c = 0; c < kChannels; ++c) {
      const auto ch = static_cast<size_t>(c);
      double mean = 0.0, lo = reference[first][ch], hi = lo;
      for (size_t k = first; k < first + per_interval; ++k) {
        mean += SensorChannelValue(run.samples[k], c) - reference[k][ch];
        lo = std::min(lo, reference[k][ch]);
        hi = std::max(hi, reference[k][ch]);
      }
      mean /= static_cast<double>(per_interval);
      double d2 = 0.0;
      for (size_t k = first; k < first + per_interval; ++k) {
        const double d = SensorChannelValue(run.samples[k], c) - reference[k][ch] - mean;
        d2 += d * d;
      }
      s.log_variance[ch] = std::log(d2 / static_cast<double>(per_interval - 1));
      s.reference_range[ch] = hi - lo;
    }
  }
  return out;
}

// A channel's quiet level over the intervals the table held still: the
// median of their log-variances and 1.4826 × the median absolute deviation
// about it (a robust σ, as the spike screening's; Hampel 1974).
struct QuietLevel {
  double log_variance = 0.0;
  double sigma = 0.0;  // of the log-variance; 0 where the channel has no scatter to depart from
};

QuietLevel QuietLevelOf(const std::vector<IntervalScatter>& intervals, const std::vector<bool>& still, int c) {
  const auto ch = static_cast<size_t>(c);
  std::vector<double> values;
  values.reserve(intervals.size());
  for (size_t i = 0; i < intervals.size(); ++i) {
    if (still[i] && std::isfinite(intervals[i].log_variance[ch])) values.push_back(intervals[i].log_variance[ch]);
  }
  QuietLevel out;
  // A channel with no scatter at rest (a counter that never turns) has no quiet level to depart from.
  if (values.size() * 2 < intervals.size()) return out;
  out.log_variance = stats::MedianInPlace(values);
  for (double& v : values) v = std::abs(v - out.log_variance);
  out.sigma = stats::kMadToSigma * stats::MedianInPlace(values);
  return out;
}

// Whether the table held its rate and specific force within the interval,
// to within the quiet scatter of every channel.
std::vector<bool> TableStill(const std::vector<IntervalScatter>& intervals) {
  std::array<double, kChannels> quiet_sigma{};
  std::vector<double> values;
  for (int c = 0; c < kChannels; ++c) {
    values.clear();
    for (const IntervalScatter& s : intervals) values.push_back(s.log_variance[static_cast<size_t>(c)]);
    quiet_sigma[static_cast<size_t>(c)] = std::exp(0.5 * stats::MedianInPlace(values));
  }
  std::vector<bool> still(intervals.size());
  for (size_t i = 0; i < intervals.size(); ++i) {
    still[i] = true;
    for (int c = 0; c < kChannels; ++c) {
      const auto ch = static_cast<size_t>(c);
      if (intervals[i].reference_range[ch] > quiet_sigma[ch]) still[i] = false;
    }
  }
  return still;
}

}  // namespace

std::vector<BenchMotion> FindBenchMotion(const BenchRun& run,
                                         const std::vector<std::array<double, 6>>& reference_measurements,
                                         double update_interval_s, double family_wise_alpha) {
  std::vector<BenchMotion> out;
  const double dt = run.NominalIntervalS();
  if (!(dt > 0.0) || reference_measurements.size() != run.samples.size()) return out;
  const auto per_interval = static_cast<size_t>(std::max(2L, std::lround(update_interval_s / dt)));
  const std::vector<IntervalScatter> intervals = ScatterPerInterval(run, reference_measurements, per_interval);
  if (intervals.size() < 2) return out;

  const std::vector<bool> still = TableStill(intervals);
  std::array<QuietLevel, kChannels> quiet;
  for (int c = 0; c < kChannels; ++c) quiet[static_cast<size_t>(c)] = QuietLevelOf(intervals, still, c);
  // Hysteresis: an interval significant among all the run's is motion, and
  // so is each neighbour significant on its own (motion is contiguous in
  // time, and a settling bench's quieter seconds carry on the move).
  const double strong =
      stats::NormalQuantile(1.0 - family_wise_alpha / (kChannels * static_cast<double>(intervals.size())));
  const double weak = stats::NormalQuantile(1.0 - family_wise_alpha / kChannels);

  // Runs of intervals over the weak threshold, kept where one passes the strong.
  BenchMotion run_of_intervals;
  bool in_run = false;
  const auto close_run = [&] {
    if (in_run && run_of_intervals.statistic > strong) out.push_back(run_of_intervals);
    in_run = false;
  };
  for (size_t i = 0; i < intervals.size(); ++i) {
    const IntervalScatter& s = intervals[i];
    double peak = 0.0;
    int peak_channel = -1;
    for (int c = 0; c < kChannels && still[i]; ++c) {
      const QuietLevel& q = quiet[static_cast<size_t>(c)];
      if (!(q.sigma > 0.0)) continue;
      const double z = (s.log_variance[static_cast<size_t>(c)] - q.log_variance) / q.sigma;
      if (z > weak && z > peak) {
        peak = z;
        peak_channel = c;
      }
    }
    if (peak_channel < 0) {
      close_run();
      continue;
    }
    if (!in_run) {
      run_of_intervals = {s.start_s, s.end_s, peak_channel, peak};
      in_run = true;
      continue;
    }
    run_of_intervals.end_s = s.end_s;
    if (peak > run_of_intervals.statistic) {
      run_of_intervals.statistic = peak;
      run_of_intervals.sensor_channel = peak_channel;
    }
  }
  close_run();
  return out;
}

bool BenchMovedWithin(const std::vector<BenchMotion>& motion, double start_s, double end_s) {
  // The first stretch that ends after start_s.
  const auto it = std::ranges::upper_bound(motion, start_s, {}, &BenchMotion::end_s);
  return it != motion.end() && it->start_s < end_s;
}

bool BenchMovedAt(const std::vector<BenchMotion>& motion, double t_s) {
  // The first stretch that ends at or after t_s.
  const auto it = std::ranges::lower_bound(motion, t_s, {}, &BenchMotion::end_s);
  return it != motion.end() && it->start_s < t_s;
}

}  // namespace insdiag::engine
