#include "insdiag/engine/ident/count_quantum.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace insdiag::engine::ident {
namespace {

double Increment(const ImuSample& s, const DriftAxis& channel, double interval_s) {
  const Eigen::Vector3d& v = channel.sensor == Sensor::kGyro ? s.gyro_rad_s : s.acc_mps2;
  return v[channel.axis] * interval_s;
}

// The smallest spacing between distinct increments of the samples read; 0
// when they hold one value or too many distinct ones to be counts.
double SmallestSpacing(const BenchRun& run, const DriftAxis& channel, double interval_s,
                       const CountQuantumOptions& options) {
  const size_t n = std::min(run.samples.size(), options.max_samples_read);
  std::vector<double> values(n);
  for (size_t k = 0; k < n; ++k) values[k] = Increment(run.samples[k], channel, interval_s);
  std::ranges::sort(values);
  // Values closer than the double rounding of the largest are one value.
  const double largest = n > 0 ? std::max(std::abs(values.front()), std::abs(values.back())) : 0.0;
  const double same = largest * 1e-12;
  double spacing = 0.0;
  size_t distinct = n > 0 ? 1 : 0;
  for (size_t k = 1; k < n; ++k) {
    const double gap = values[k] - values[k - 1];
    if (gap <= same) continue;
    ++distinct;
    spacing = spacing == 0.0 ? gap : std::min(spacing, gap);
  }
  if (static_cast<double>(distinct) > options.max_distinct_share * static_cast<double>(n)) return 0.0;
  return spacing;
}

bool AllOnLattice(const BenchRun& run, const DriftAxis& channel, double interval_s, double quantum,
                  const CountQuantumOptions& options) {
  return std::ranges::all_of(run.samples, [&](const ImuSample& s) {
    const double count = Increment(s, channel, interval_s) / quantum;
    return std::abs(count - std::round(count)) <= options.count_tolerance * std::max(1.0, std::abs(count));
  });
}

}  // namespace

std::array<std::optional<double>, DriftAxis::kCount> CountQuanta(const BenchRun& run,
                                                                 const CountQuantumOptions& options) {
  std::array<std::optional<double>, DriftAxis::kCount> out;
  const double interval_s = run.NominalIntervalS();
  if (!(interval_s > 0.0)) return out;
  std::array<double, DriftAxis::kCount> spacing{};
  for (const DriftAxis d : DriftAxis::All())
    spacing[static_cast<size_t>(d.Index())] = SmallestSpacing(run, d, interval_s, options);
  for (const DriftAxis d : DriftAxis::All()) {
    double sensor_spacing = 0.0;
    for (int axis = 0; axis < 3; ++axis) {
      const double s = spacing[static_cast<size_t>(DriftAxis{d.sensor, axis}.Index())];
      if (s > 0.0) sensor_spacing = sensor_spacing == 0.0 ? s : std::min(sensor_spacing, s);
    }
    for (const double q : {sensor_spacing, spacing[static_cast<size_t>(d.Index())]}) {
      if (q > 0.0 && AllOnLattice(run, d, interval_s, q, options)) {
        out[static_cast<size_t>(d.Index())] = q;
        break;
      }
    }
  }
  return out;
}

}  // namespace insdiag::engine::ident
