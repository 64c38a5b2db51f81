// Scenarios shared by the Allan analysis tests (allan_test.cc) and their
// cross-check against an independent computation (allan_cross_check_test.cc).
#pragma once

#include <cstdio>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "insdiag/engine/ident/allan.h"
#include "scenarios.h"

namespace insdiag::engine::ident::allan_scenarios {

using testing::kDeg;
using testing::kDegPerHour;
using testing::kMicroG;
using K = sim::TableSegment::Kind;

// Holds of 900, 90, 40 and 300 s between turns: three static segments (the
// 40-s hold is too short), two of them shorter than the largest clusters.
inline sim::TableProfile HoldsProfile() {
  sim::TableProfile p;
  p.name = "holds";
  p.angular_acceleration_rad_s2 = 10.0 * kDeg;
  p.thermal.ambient_degc = 25.0;
  p.segments = {{K::kHold, 900.0, 0, 0, 0},        {K::kRotateOuter, 36.0, 10.0 * kDeg, 0, 0},
                {K::kHold, 90.0, 0, 0, 0},         {K::kRotateInner, 18.0, 10.0 * kDeg, 0, 0},
                {K::kHold, 40.0, 0, 0, 0},         {K::kMoveTo, 0, 10.0 * kDeg, 0, 0},
                {K::kHold, 300.0, 0, 0, 0}};
  return p;
}

inline std::string Number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}

// The INS-2000-class unit with one extra noise term per axis. Quantisation
// sits where the signal sweeps through the quantisation levels (the gyro's x
// axis sees the Earth's rate, the accelerometer's z axis gravity): with the
// per-sample noise 20 times below the quantum, quantisation of a still,
// level axis leaves a slow deterministic pattern, not white angle noise.
struct HiddenTerms {
  double gyro_q = 3.35e-7;  // rad: 3Q²/τ² = N²/τ at τ = 1 s (x)
  double acc_q = 5.66e-5;   // m/s (z)
  double gyro_k = 3e-8;     // rad/s/√s (y)
  double acc_k = 1e-4;      // m/s²/√s (x)
  GaussMarkov gyro_gm{0.05 * kDegPerHour, 60.0};  // z
  GaussMarkov acc_gm{20.0 * kMicroG, 60.0};       // y
};
inline constexpr int kGyroQ = 0, kGyroK = 1, kGyroGm = 2;
inline constexpr int kAccQ = 2, kAccK = 0, kAccGm = 1;
inline constexpr const char* kAxisName[3] = {"x", "y", "z"};

inline sim::SimulatedUnit HiddenTermsUnit(const HiddenTerms& h) {
  sim::SimulatedUnit u = testing::NavigationGradeUnit();
  u.gyro.quantization[kGyroQ] = h.gyro_q;
  u.acc.quantization[kAccQ] = h.acc_q;
  auto g = sim::ParseTrueEffect(std::string("gyro_bias_rw.") + kAxisName[kGyroK] + "=" + Number(h.gyro_k));
  auto a = sim::ParseTrueEffect(std::string("acc_bias_rw.") + kAxisName[kAccK] + "=" + Number(h.acc_k));
  EXPECT_TRUE(g.ok() && a.ok());
  u.effects = {g->front(), a->front()};
  u.gyro.bias[kGyroGm] = h.gyro_gm;
  u.acc.bias[kAccGm] = h.acc_gm;
  return u;
}

inline const AllanChannel& Channel(const AllanResult& r, const std::string& name) {
  for (const AllanChannel& c : r.channels) {
    if (c.name == name) return c;
  }
  ADD_FAILURE() << "no channel " << name;
  return r.channels.front();
}

inline std::string Describe(const AllanChannel& ch) {
  std::ostringstream s;
  s << ch.name << ": " << (ch.fit.markov_structure ? "markov" : "flicker") << " set, χ² " << ch.fit.generalized_chi2
    << " on " << ch.fit.dof << " (p " << ch.fit.p_value << "), δ " << ch.fit.discrepancy << ";";
  for (int k = 0; k < kAllanParameterCount; ++k) {
    const AllanTermEstimate& t = ch.fit.parameters[static_cast<size_t>(k)];
    if (t.included) s << " " << AllanParameterName(static_cast<AllanParameter>(k)) << " " << t.value << " ± " << t.std_error;
  }
  for (const std::string& u : ch.fit.unresolved) s << "; dropped " << u;
  return s.str();
}

}  // namespace insdiag::engine::ident::allan_scenarios
