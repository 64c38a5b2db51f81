// Simulated units and runs shared by the engine tests.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "insdiag/engine/analysis.h"
#include "insdiag/engine/sim/simulator.h"

namespace insdiag::engine::testing {

inline constexpr double kDeg = std::numbers::pi / 180.0;
inline constexpr double kDegPerHour = kDeg / 3600.0;
inline constexpr double kMicroG = 9.80665e-6;

inline Site TestSite() { return {55.5672 * kDeg, 38.15 * kDeg, 125.0}; }

// A navigation-grade unit of the INS-2000 class: DTG drift 0.01°/h with a
// half-hour correlation time, ARW 0.002°/√h, accelerometer bias 30 µg,
// VRW 10 µg/√Hz.
inline sim::SimulatedUnit NavigationGradeUnit() {
  sim::SimulatedUnit u;
  u.serial = "SIM-0001";
  u.type = "INS-2000";
  for (int i = 0; i < 3; ++i) {
    u.gyro.bias[static_cast<size_t>(i)] = {0.01 * kDegPerHour, 1800.0};
    u.acc.bias[static_cast<size_t>(i)] = {30.0 * kMicroG, 1800.0};
  }
  u.gyro.white_noise_density.setConstant(0.002 * kDeg / 60.0);
  u.acc.white_noise_density.setConstant(10.0 * kMicroG);
  return u;
}

// The unit's true base model as an ErrorModel, with the analysis' bench accuracy.
inline ErrorModel TrueBaseModel(const sim::SimulatedUnit& u) {
  ErrorModel m;
  m.gyro = u.gyro;
  m.acc = u.acc;
  m.reference = AnalysisOptions{}.reference;
  return m;
}

// A profile made in the test: `still_s` level and still, then turns about
// body z, y and x at 10°/s, then still to the end.
inline sim::TableProfile ShortTurnsProfile(double still_s, double total_s) {
  sim::TableProfile p;
  p.name = "short-turns";
  p.angular_acceleration_rad_s2 = 10.0 * kDeg;
  p.thermal.ambient_degc = 25.0;
  using K = sim::TableSegment::Kind;
  p.segments = {{K::kHold, still_s, 0, 0, 0},
                {K::kRotateOuter, 73.0, 10.0 * kDeg, 0, 0},
                {K::kHold, 60.0, 0, 0, 0},
                {K::kRotateInner, 73.0, 10.0 * kDeg, 0, 0},
                {K::kMoveTo, 0, 10.0 * kDeg, 0, 90.0 * kDeg},
                {K::kRotateOuter, 73.0, -10.0 * kDeg, 0, 0},
                {K::kMoveTo, 0, 10.0 * kDeg, 0, 0}};
  double used = still_s + 73.0 * 3 + 60.0 + 18.0;
  if (total_s > used) p.segments.push_back({K::kHold, total_s - used, 0, 0, 0});
  return p;
}

inline sim::SimulatedRun SimulateOrDie(const sim::SimulatedUnit& unit, const sim::TableProfile& profile,
                                       double rate_hz, uint64_t seed) {
  sim::SimulationOptions o;
  o.sample_rate_hz = rate_hz;
  o.seed = seed;
  o.site = TestSite();
  auto run = sim::Simulate(unit, profile, o);
  EXPECT_TRUE(run.ok()) << run.status();
  return *std::move(run);
}

inline sim::TableProfile BuiltinProfileOrDie(const std::string& name) {
  auto p = sim::BuiltinProfile(name);
  EXPECT_TRUE(p.ok()) << p.status();
  return *std::move(p);
}

}  // namespace insdiag::engine::testing
