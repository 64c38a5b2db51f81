#include "insdiag/engine/monitor/sample_screening.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace insdiag::engine {
namespace {

double& Channel(ImuSample& s, int c) { return c < 3 ? s.gyro_rad_s[c] : s.acc_mps2[c - 3]; }

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
  std::vector<double> departure(static_cast<size_t>(n - 2 * w));
  auto local_median = [&](int c, long k) {
    for (long j = -w; j <= w; ++j) window[static_cast<size_t>(j + w)] = Channel(run.samples[static_cast<size_t>(k + j)], c);
    return MedianOf(window);
  };
  for (int c = 0; c < 6; ++c) {
    for (long k = w; k < n - w; ++k) {
      departure[static_cast<size_t>(k - w)] = Channel(run.samples[static_cast<size_t>(k)], c) - local_median(c, k);
    }
    std::vector<double> magnitude(departure.size());
    std::transform(departure.begin(), departure.end(), magnitude.begin(), [](double d) { return std::abs(d); });
    double sigma = 1.4826 * MedianOf(magnitude);
    if (sigma <= 0.0) {
      // Coarsely quantised, mostly constant data: the smallest non-zero departure
      // is one quantum, the least a spike must exceed many times over.
      double smallest = 0.0;
      for (double m : magnitude) {
        if (m > 0.0 && (smallest == 0.0 || m < smallest)) smallest = m;
      }
      sigma = smallest;
    }
    if (sigma <= 0.0) continue;
    for (long k = w; k < n - w; ++k) {
      const double z = std::abs(departure[static_cast<size_t>(k - w)]) / sigma;
      if (z <= options.threshold) continue;
      ImuSample& s = run.samples[static_cast<size_t>(k)];
      const double median = Channel(s, c) - departure[static_cast<size_t>(k - w)];
      outliers.push_back({static_cast<size_t>(k), c, s.t_s, z, Channel(s, c), median});
    }
  }
  for (const SampleOutlier& o : outliers) Channel(run.samples[o.sample], o.sensor_channel) = o.replacement;
  std::sort(outliers.begin(), outliers.end(), [](const SampleOutlier& a, const SampleOutlier& b) {
    return a.sample != b.sample ? a.sample < b.sample : a.sensor_channel < b.sensor_channel;
  });
  return outliers;
}

}  // namespace insdiag::engine
