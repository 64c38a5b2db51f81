#include "insdiag/engine/monitor/sample_screening.h"

#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <cmath>

#include "insdiag/engine/nav/rotation.h"
#include "insdiag/engine/nav/strapdown.h"
#include "insdiag/engine/nav/table_motion.h"
#include "insdiag/engine/nav/wgs84.h"
#include "insdiag/engine/numerics/parallel_map.h"
#include "insdiag/engine/stats/robust.h"

namespace insdiag::engine {
namespace {

// What a perfect unit would have measured over each sample interval, from the
// table's reference attitude: the mean body rate Log(C_{k−1}ᵀ C_k)/Δt plus the
// Earth's rate, and the mean specific force (J/h) C_{k−1}ᵀ (−gⁿ) of a rotation
// at constant rate (strapdown.h). The table's motion — ramps, stops, gravity
// turning through the axes — is in it, so what is left is the sensor's own
// error: smooth drifts and noise, against which a spike stands out even where
// the raw signal bends faster than a median can follow (the corners of a
// rate profile sampled at 10 Hz).

// Departures used to estimate the channel's robust σ.
constexpr long kScaleSampleCount = 20000;

double QuantileOf(std::vector<double>& v, double p) {
  auto at = v.begin() + static_cast<std::ptrdiff_t>(p * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), at, v.end());
  return *at;
}

// Quantiles of |d| for Gaussian d of standard deviation 1: Φ⁻¹(0.75) and Φ⁻¹(0.95).
constexpr double kHalfNormalMedian = 0.6744897501960817;
constexpr double kHalfNormalQuantile90 = 1.6448536269514722;

// The channel's robust σ from |departures|. 1.4826·MAD (= MAD / Φ⁻¹(0.75))
// collapses on coarsely quantised samples, where more than half of the
// departures sit at zero, or within the timing jitter of zero once increments
// are divided by measured intervals; every quantum step would then be a
// "spike". The 90th percentile / Φ⁻¹(0.95) estimates the same σ for Gaussian
// noise and stays at the quantisation level there; the larger is taken.
double RobustSigma(std::vector<double>& magnitude) {
  const double from_median = stats::MedianInPlace(magnitude) / kHalfNormalMedian;
  return std::max(from_median, QuantileOf(magnitude, 0.9) / kHalfNormalQuantile90);
}

}  // namespace

std::vector<std::array<double, 6>> ReferenceMeasurements(const BenchRun& run,
                                                         const nav::RunCompensations& compensations) {
  const auto& samples = run.samples;
  std::vector<std::array<double, 6>> expected(samples.size());
  if (samples.size() < 2) return expected;
  const auto& site = run.metadata.site;
  const Eigen::Vector3d w_ie_n = wgs84::EarthRateNed(site.latitude_rad);
  const Eigen::Vector3d minus_g_n = -nav::GravityNed(site.latitude_rad, site.height_m);
  // Each interval's values follow from the reference alone: contiguous
  // blocks of samples on every core.
  const size_t blocks = static_cast<size_t>(numerics::WorkerThreads());
  numerics::ParallelMap(blocks, [&](size_t b) {
    const size_t begin = std::max<size_t>(1, samples.size() * b / blocks);
    const size_t end = samples.size() * (b + 1) / blocks;
    Eigen::Matrix3d C1 = nav::EulerToDcm(samples[begin - 1].ref_rpy_rad);
    for (size_t k = begin; k < end; ++k) {
      const Eigen::Matrix3d C0 = C1;
      C1 = nav::EulerToDcm(samples[k].ref_rpy_rad);
      const double dt = samples[k].t_s - samples[k - 1].t_s;
      // The body rate's integral is the interval's rotation vector less its
      // coning, and the mean rotation of gravity is the constant-rate one with
      // the motion's shape added (nav/table_motion.h): a rate that steps inside
      // a sample, or one axis stopping as the other starts, is not a spike.
      const nav::IntervalCompensation& shape = compensations.At(k);
      const Eigen::Vector3d dtheta =
          nav::QuaternionToRotationVector(Eigen::Quaterniond(C0.transpose() * C1)) - shape.coning_rad;
      const Eigen::Vector3d rate = dtheta / dt + C0.transpose() * w_ie_n;
      const Eigen::Matrix3d mean_rotation =
          (nav::MeanBodyRotation(dtheta).inverse() + shape.velocity_map_correction).inverse();
      const Eigen::Vector3d force = mean_rotation * (C0.transpose() * minus_g_n);
      expected[k] = {rate.x(), rate.y(), rate.z(), force.x(), force.y(), force.z()};
    }
    return true;
  });
  expected[0] = expected[1];
  return expected;
}

std::vector<SampleOutlier> ScreenAndRepairSpikes(BenchRun& run, const ScreeningOptions& options) {
  return ScreenAndRepairSpikes(run, ReferenceMeasurements(run, nav::RunCompensations(run)), options);
}

std::vector<SampleOutlier> ScreenAndRepairSpikes(BenchRun& run, const std::vector<std::array<double, 6>>& expected,
                                                 const ScreeningOptions& options) {
  std::vector<SampleOutlier> outliers;
  const int w = options.half_window;
  const auto n = static_cast<long>(run.samples.size());
  if (n < 2 * w + 1) return outliers;
  // The sample's departure from the reference motion.
  auto residual = [&](int c, long k) {
    const auto i = static_cast<size_t>(k);
    return SensorChannelValue(run.samples[i], c) - expected[i][static_cast<size_t>(c)];
  };
  std::vector<double> window(static_cast<size_t>(2 * w + 1));
  auto departure_at = [&](int c, long k) {
    for (long j = -w; j <= w; ++j) window[static_cast<size_t>(j + w)] = residual(c, k + j);
    return residual(c, k) - stats::MedianInPlace(window);
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
    double sigma = RobustSigma(magnitude);
    if (sigma <= 0.0) {
      // Coarsely quantised, mostly constant data: the smallest non-zero departure
      // is one quantum, the least a spike must exceed many times over.
      double smallest = 0.0;
      for (long k = w; k < n - w; ++k) {
        const double m = std::abs(residual(c, k) - residual(c, k - 1));
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
      const double mid = 0.5 * (residual(c, k - 1) + residual(c, k + 1));
      if (std::abs(residual(c, k) - mid) > pre) candidates.push_back(k);
    }
    for (long k : candidates) {
      const double departure = departure_at(c, k);
      const double z = std::abs(departure) / sigma;
      if (z <= options.threshold) continue;
      ImuSample& s = run.samples[static_cast<size_t>(k)];
      const double value = SensorChannelValue(s, c);
      outliers.push_back({static_cast<size_t>(k), c, s.t_s, z, value, value - departure});
    }
  }
  for (const SampleOutlier& o : outliers) {
    SensorChannelValue(run.samples[o.sample], o.sensor_channel) = o.replacement;
  }
  std::sort(outliers.begin(), outliers.end(), [](const SampleOutlier& a, const SampleOutlier& b) {
    return a.sample != b.sample ? a.sample < b.sample : a.sensor_channel < b.sensor_channel;
  });
  return outliers;
}

}  // namespace insdiag::engine
