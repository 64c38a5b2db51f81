#include "support/synthetic_run.h"

#include <cmath>
#include <numbers>
#include <random>

namespace insdiag::testing {

engine::BenchRun SyntheticStaticRun(std::size_t sample_count, double rate_hz, std::uint32_t seed,
                                    bool with_temperature) {
  constexpr double kEarthRateRadS = 7.2921150e-5;
  constexpr double kGravityMps2 = 9.8154;
  engine::BenchRun run;
  run.metadata.format = "insdiag-bench-run/1";
  run.metadata.unit_serial = "INS-2000-0042";
  run.metadata.unit_type = "INS-2000";
  run.metadata.site = {.latitude_rad = 55.5672 * std::numbers::pi / 180.0,
                       .longitude_rad = 38.15 * std::numbers::pi / 180.0,
                       .height_m = 125.0};
  run.metadata.datasheet.gyro_arw_rad_rts = 2.9e-6;
  run.metadata.extra = {{"bench", "table-3"}, {"operator", "synthetic"}};
  run.has_temperature = with_temperature;

  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gyro_noise(0.0, 1e-6);
  std::normal_distribution<double> acc_noise(0.0, 1e-3);
  const double lat = run.metadata.site.latitude_rad;
  // Level, heading north: body axes = NED.
  const Eigen::Vector3d earth_rate(kEarthRateRadS * std::cos(lat), 0.0, -kEarthRateRadS * std::sin(lat));
  const Eigen::Vector3d specific_force(0.0, 0.0, -kGravityMps2);
  run.samples.reserve(sample_count);
  for (std::size_t k = 0; k < sample_count; ++k) {
    engine::ImuSample s;
    s.t_s = static_cast<double>(k + 1) / rate_hz;
    for (int axis = 0; axis < 3; ++axis) {
      s.gyro_rad_s[axis] = earth_rate[axis] + gyro_noise(rng);
      s.acc_mps2[axis] = specific_force[axis] + acc_noise(rng);
    }
    s.temp_degc = with_temperature ? 24.0 + 0.5 * static_cast<double>(k) / static_cast<double>(sample_count) : 0.0;
    run.samples.push_back(s);
  }
  return run;
}

}  // namespace insdiag::testing
