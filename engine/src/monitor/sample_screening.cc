#include "insdiag/engine/monitor/sample_screening.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace insdiag::engine {
namespace {

double& Channel(ImuSample& s, int c) { return c < 3 ? s.gyro_rad_s[c] : s.acc_mps2[c - 3]; }

// Departures used to estimate the channel's robust σ.
constexpr long kScaleSampleCount = 20000;

double MedianOf(std::vector<double>& v) {
  auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace

std::vector<SampleOutlier> ScreenAndRepairSpikes(BenchRun& run, const ScreeningOptions& options) {
  std::vector<SampleOutlier> outliers;
  const int w = options.half_window;
  const auto n = static_cast<long>(run.samples.size());
  if (n < 2 * w + 1) return outliers;
  std::vector<double> window(static_cast<size_t>(2 * w + 1));
  auto departure_at = [&](int c, long k) {
    for (long j = -w; j <= w; ++j) window[static_cast<size_t>(j + w)] = Channel(run.samples[static_cast<size_t>(k + j)], c);
    return Channel(run.samples[static_cast<size_t>(k)], c) - MedianOf(window);
  };
  // σ from a systematic subsample of the departures: a robust scale needs
  // thousands of values, not all of them (the full Hampel pass would cost
  // more than the filter itself).
  const long stride = std::max(1L, (n - 2 * w) / kScaleSampleCount);
  std::vector<double> magnitude;
  std::vector<long> candidates;
  for (int c = 0; c < 6; ++c) {
    magnitude.clear();
    for (long k = w; k < n - w; k += stride) magnitude.push_back(std::abs(departure_at(c, k)));
    double sigma = 1.4826 * MedianOf(magnitude);
    if (sigma <= 0.0) {
      // Coarsely quantised, mostly constant data: the smallest non-zero departure
      // is one quantum, the least a spike must exceed many times over.
      double smallest = 0.0;
      for (long k = w; k < n - w; ++k) {
        const double m = std::abs(Channel(run.samples[static_cast<size_t>(k)], c) -
                                  Channel(run.samples[static_cast<size_t>(k - 1)], c));
        if (m > 0.0 && (smallest == 0.0 || m < smallest)) smallest = m;
      }
      sigma = smallest;
    }
    if (sigma <= 0.0) continue;
    // Pre-screen: a spike of size S moves x_k − (x_{k−1} + x_{k+1})/2 by S; noise
    // moves it by about 1.2σ. Only samples past half the threshold there get the
    // exact median test (table ramps pass the pre-screen and fail the median test).
    candidates.clear();
    const double pre = 0.5 * options.threshold * sigma;
    for (long k = w; k < n - w; ++k) {
      const double x = Channel(run.samples[static_cast<size_t>(k)], c);
      const double mid = 0.5 * (Channel(run.samples[static_cast<size_t>(k - 1)], c) +
                                Channel(run.samples[static_cast<size_t>(k + 1)], c));
      if (std::abs(x - mid) > pre) candidates.push_back(k);
    }
    for (long k : candidates) {
      const double departure = departure_at(c, k);
      const double z = std::abs(departure) / sigma;
      if (z <= options.threshold) continue;
      ImuSample& s = run.samples[static_cast<size_t>(k)];
      outliers.push_back({static_cast<size_t>(k), c, s.t_s, z, Channel(s, c), Channel(s, c) - departure});
    }
  }
  for (const SampleOutlier& o : outliers) Channel(run.samples[o.sample], o.sensor_channel) = o.replacement;
  std::sort(outliers.begin(), outliers.end(), [](const SampleOutlier& a, const SampleOutlier& b) {
    return a.sample != b.sample ? a.sample < b.sample : a.sensor_channel < b.sensor_channel;
  });
  return outliers;
}

}  // namespace insdiag::engine
