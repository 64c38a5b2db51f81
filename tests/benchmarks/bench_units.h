// Simulated units shared by the benchmark programs (no GoogleTest here: the
// tests' scenarios.h needs it).
#pragma once

#include <numbers>

#include "insdiag/engine/sim/simulator.h"

namespace insdiag::engine::bench {

inline constexpr double kDeg = std::numbers::pi / 180.0;

// The engine tests' INS-2000-class unit: drift 0.01 °/h and 30 µg with
// T = 1800 s, ARW 0.002 °/√h, VRW 10 µg/√Hz.
inline sim::SimulatedUnit NavigationGradeUnit() {
  sim::SimulatedUnit u;
  u.serial = "BENCH";
  for (auto& b : u.gyro.bias) b = {0.01 * kDeg / 3600.0, 1800.0};
  for (auto& b : u.acc.bias) b = {30e-6 * 9.80665, 1800.0};
  u.gyro.white_noise_density.setConstant(0.002 * kDeg / 60.0);
  u.acc.white_noise_density.setConstant(10e-6 * 9.80665);
  return u;
}

// 100 Hz at the engine tests' site.
inline sim::SimulationOptions HundredHertz(uint64_t seed) {
  sim::SimulationOptions o;
  o.sample_rate_hz = 100.0;
  o.seed = seed;
  o.site = {55.5672 * kDeg, 38.15 * kDeg, 125.0};
  return o;
}

}  // namespace insdiag::engine::bench
