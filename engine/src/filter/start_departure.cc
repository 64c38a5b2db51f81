#include "insdiag/engine/filter/start_departure.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "insdiag/engine/nav/rotation.h"
#include "insdiag/engine/nav/wgs84.h"

namespace insdiag::engine {

size_t StillStartEnd(const BenchRun& run, double still_tolerance_rad) {
  const Eigen::Vector3d& start_rpy = run.samples.front().ref_rpy_rad;
  size_t k = 1;
  for (; k < run.samples.size() && !run.StartsSegment(k); ++k) {
    const Eigen::Vector3d& rpy = run.samples[k].ref_rpy_rad;
    bool still = true;
    for (int i = 0; i < 3; ++i) {
      still = still && std::abs(std::remainder(rpy[i] - start_rpy[i], 2.0 * std::numbers::pi)) <= still_tolerance_rad;
    }
    if (!still) break;
  }
  return k;
}

Vector6d PerfectReadingAtStart(const BenchRun& run) {
  const Site& site = run.metadata.site;
  const Eigen::Matrix3d C_n_b = nav::EulerToDcm(run.samples.front().ref_rpy_rad).transpose();
  Vector6d perfect;
  perfect << C_n_b * wgs84::EarthRateNed(site.latitude_rad),
      C_n_b * Eigen::Vector3d(0.0, 0.0, -wgs84::NormalGravityMps2(site.latitude_rad, site.height_m));
  return perfect;
}

StartDeparture MeasureStartDeparture(const BenchRun& run, const ErrorModel& model, double update_interval_s,
                                     double still_tolerance_rad, std::optional<double> bench_moved_from_s) {
  StartDeparture out;
  if (run.samples.size() < 3) return out;
  const size_t end = StillStartEnd(run, still_tolerance_rad);
  if (end < 3) return out;
  const double t0_s = run.samples.front().t_s;
  const double still_s = run.samples[end - 1].t_s - t0_s;
  // Before the bench first moved, the departure is the unit's; a window the
  // bench's motion follows closely may hold its start (a tilt the scatter
  // does not show), so the window must end a window's length before it.
  const double quiet_s = bench_moved_from_s.has_value() ? *bench_moved_from_s - t0_s : still_s;

  const Vector6d perfect = PerfectReadingAtStart(run);

  std::array<double, kSensorAxisCount> window_s{};
  for (int i = 0; i < kSensorAxisCount; ++i) {
    const SensorTriadModel& triad = i < 3 ? model.gyro : model.acc;
    const double density = triad.white_noise_density[i % 3];
    const double sigma = triad.bias[static_cast<size_t>(i % 3)].sigma;
    if (!(sigma > 0.0)) continue;
    window_s[static_cast<size_t>(i)] = std::max(update_interval_s, density * density / (sigma * sigma));
  }

  // Sums of the reading less the perfect one over each axis' window and over the whole still start.
  Vector6d whole = Vector6d::Zero(), window = Vector6d::Zero();
  std::array<size_t, kSensorAxisCount> in_window{};
  for (size_t k = 1; k < end; ++k) {
    const ImuSample& s = run.samples[k];
    Vector6d r;
    r << s.gyro_rad_s, s.acc_mps2;
    r -= perfect;
    whole += r;
    for (int i = 0; i < kSensorAxisCount; ++i) {
      if (s.t_s - t0_s <= window_s[static_cast<size_t>(i)]) {
        window[i] += r[i];
        ++in_window[static_cast<size_t>(i)];
      }
    }
  }
  whole /= static_cast<double>(end - 1);

  for (int i = 0; i < kSensorAxisCount; ++i) {
    const auto a = static_cast<size_t>(i);
    // The window must fit in the still start with the stretch beyond it to compare against.
    if (window_s[a] == 0.0 || 2.0 * window_s[a] > std::min(still_s, quiet_s) || in_window[a] == 0) continue;
    const SensorTriadModel& triad = i < 3 ? model.gyro : model.acc;
    const double density = triad.white_noise_density[i % 3];
    const double quantum = triad.quantization[i % 3];
    const double w = window_s[a];
    const double noise_variance = density * density / w + 2.0 * quantum * quantum / (w * w);
    const double departure = window[i] / static_cast<double>(in_window[a]) - whole[i];
    out.departure[a] = departure;
    out.window_s[a] = w;
    out.std_error[a] = std::sqrt(noise_variance);
    out.start_square[a] = std::max(0.0, departure * departure - noise_variance);
  }
  return out;
}

}  // namespace insdiag::engine
