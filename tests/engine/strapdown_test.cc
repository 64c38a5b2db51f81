// Mechanisation against the table's exact motion: with perfect sensors the
// free-inertial solution must stay at the site.
#include "insdiag/engine/nav/strapdown.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include "insdiag/engine/nav/rotation.h"
#include "insdiag/engine/nav/table_motion.h"
#include "insdiag/engine/nav/wgs84.h"
#include "insdiag/engine/sim/simulator.h"

namespace insdiag::engine {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

Site TestSite() { return {55.5672 * kDeg, 38.15 * kDeg, 125.0}; }

struct DriftExtremes {
  double horizontal_position_m = 0.0;
  double horizontal_velocity_mps = 0.0;
  double vertical_position_m = 0.0;
  double vertical_velocity_mps = 0.0;
  double attitude_rad = 0.0;
};

// Runs the mechanisation over the samples whose time is ≤ until_s and
// returns the largest departures from the site and the reference attitude.
// With `hold_vertical` the height and vertical velocity are reset to the
// site's after each step: the free-inertial vertical channel diverges with a
// time constant of √(R/2g) ≈ 10 min, and over an hour its growth would couple
// into the horizontal channels and hide what this test checks.
DriftExtremes FreeInertialDrift(const BenchRun& run, double until_s, bool hold_vertical) {
  const Site site = run.metadata.site;
  nav::NavState s;
  s.q_b_n = Eigen::Quaterniond(nav::EulerToDcm(run.samples[0].ref_rpy_rad));
  s.latitude_rad = site.latitude_rad;
  s.longitude_rad = site.longitude_rad;
  s.height_m = site.height_m;
  const double rm = wgs84::MeridianRadiusM(site.latitude_rad) + site.height_m;
  const double rn = wgs84::PrimeVerticalRadiusM(site.latitude_rad) + site.height_m;
  DriftExtremes worst;
  nav::ReferenceMotion motion(run);
  for (size_t k = 1; k < run.samples.size() && run.samples[k].t_s <= until_s; ++k) {
    const ImuSample& smp = run.samples[k];
    const double dt = smp.t_s - run.samples[k - 1].t_s;
    const nav::ImuIncrement current{smp.gyro_rad_s * dt, smp.acc_mps2 * dt};
    s = nav::PropagateStrapdown(s, current, motion.Compensation(k), dt);
    if (hold_vertical) {
      s.height_m = site.height_m;
      s.v_n_mps.z() = 0.0;
    }
    const double north = (s.latitude_rad - site.latitude_rad) * rm;
    const double east = (s.longitude_rad - site.longitude_rad) * rn * std::cos(site.latitude_rad);
    worst.horizontal_position_m = std::max(worst.horizontal_position_m, std::hypot(north, east));
    worst.horizontal_velocity_mps = std::max(worst.horizontal_velocity_mps, s.v_n_mps.head<2>().norm());
    worst.vertical_position_m = std::max(worst.vertical_position_m, std::abs(s.height_m - site.height_m));
    worst.vertical_velocity_mps = std::max(worst.vertical_velocity_mps, std::abs(s.v_n_mps.z()));
    const Eigen::Matrix3d C_ref = nav::EulerToDcm(smp.ref_rpy_rad);
    const Eigen::AngleAxisd err(Eigen::Quaterniond(C_ref.transpose() * s.q_b_n.toRotationMatrix()));
    worst.attitude_rad = std::max(worst.attitude_rad, std::abs(err.angle()));
  }
  return worst;
}

sim::SimulatedRun PerfectRun(const std::string& profile_name, double rate_hz) {
  auto profile = sim::BuiltinProfile(profile_name);
  EXPECT_TRUE(profile.ok()) << profile.status();
  sim::SimulationOptions options;
  options.sample_rate_hz = rate_hz;
  options.site = TestSite();
  options.perfect_sensors = true;
  auto run = sim::Simulate(sim::SimulatedUnit{}, *profile, options);
  EXPECT_TRUE(run.ok()) << run.status();
  return *std::move(run);
}

// The midway rotation the filter takes for a sample's attitude is slerp at
// ½, also when the two quaternions lie in opposite hemispheres (q and −q are
// one rotation).
TEST(Rotation, MidwayIsSlerpAtOneHalf) {
  std::mt19937_64 rng(17);
  std::normal_distribution<double> normal;
  for (int i = 0; i < 200; ++i) {
    const Eigen::Quaterniond a = Eigen::Quaterniond(Eigen::Vector4d(normal(rng), normal(rng), normal(rng), normal(rng))).normalized();
    const Eigen::Vector3d step(normal(rng), normal(rng), normal(rng));
    Eigen::Quaterniond b = (a * nav::RotationVectorToQuaternion(0.5 * step)).normalized();
    if (i % 2 == 1) b.coeffs() = -b.coeffs();
    const Eigen::Matrix3d expected = a.slerp(0.5, b).toRotationMatrix();
    EXPECT_LT((nav::Midway(a, b).toRotationMatrix() - expected).cwiseAbs().maxCoeff(), 1e-12) << "case " << i;
  }
}

TEST(Strapdown, PerfectSensorsStayAtTheSiteThroughAnHourOfTableMotion) {
  const sim::SimulatedRun sim_run = PerfectRun("rotations", 100.0);
  const DriftExtremes hour = FreeInertialDrift(sim_run.run, 3600.0, /*hold_vertical=*/true);
  EXPECT_LT(hour.horizontal_position_m, 0.01);
  EXPECT_LT(hour.horizontal_velocity_mps, 0.001);
  // The attitude through every turn, including the spins with body x vertical.
  EXPECT_LT(hour.attitude_rad, 1e-9);
  const DriftExtremes ten_minutes = FreeInertialDrift(sim_run.run, 600.0, /*hold_vertical=*/false);
  EXPECT_LT(ten_minutes.vertical_position_m, 0.01);
  EXPECT_LT(ten_minutes.vertical_velocity_mps, 0.001);
}

TEST(Strapdown, PerfectSensorsStayAtTheSiteThroughTiltsOnASkewMount) {
  const sim::SimulatedRun sim_run = PerfectRun("positions", 100.0);
  const DriftExtremes hour = FreeInertialDrift(sim_run.run, 3600.0, /*hold_vertical=*/true);
  EXPECT_LT(hour.horizontal_position_m, 0.01);
  EXPECT_LT(hour.horizontal_velocity_mps, 0.001);
  EXPECT_LT(hour.attitude_rad, 1e-9);
  const DriftExtremes ten_minutes = FreeInertialDrift(sim_run.run, 600.0, /*hold_vertical=*/false);
  EXPECT_LT(ten_minutes.vertical_position_m, 0.01);
  EXPECT_LT(ten_minutes.vertical_velocity_mps, 0.001);
}

// A table whose rate changes within a sample — instantly (an acceleration
// far beyond any sample rate) or as a ramp that starts and ends inside
// samples — at 10, 50 and 100 Hz: with perfect sensors the free-inertial
// solution stays at the site to within a small share of one update's
// velocity noise (a navigation-grade unit's 10 µg/√Hz is 1e-4 m/s over a
// second). Before the mechanisation took the motion from the reference, the
// two-sample terms left 1.4e-3 m/s per rate change at 10 Hz.
struct RateChange {
  double rate_hz;
  double acceleration_deg_s2;  // 1e7: a step within one sample
};

class TableRateChanges : public ::testing::TestWithParam<RateChange> {};

TEST_P(TableRateChanges, LeaveNoVelocityErrorInTheMechanisation) {
  const RateChange c = GetParam();
  sim::TableProfile profile;
  profile.angular_acceleration_rad_s2 = c.acceleration_deg_s2 * kDeg;
  profile.mount_rpy_rad = {0.0, 0.0, 45.0 * kDeg};
  using K = sim::TableSegment::Kind;
  // Durations off every sample grid, so that each rate change falls inside a sample.
  profile.segments = {{K::kHold, 10.013, 0, 0, 0},       {K::kRotateOuter, 36.0371, 10.0 * kDeg, 0, 0},
                      {K::kHold, 5.0419, 0, 0, 0},       {K::kRotateInner, 9.0277, 10.0 * kDeg, 0, 0},
                      {K::kHold, 5.0531, 0, 0, 0},       {K::kRotateOuter, 36.0233, -10.0 * kDeg, 0, 0},
                      {K::kHold, 5.0377, 0, 0, 0},       {K::kRotateInner, 9.0191, -10.0 * kDeg, 0, 0},
                      {K::kHold, 10.0, 0, 0, 0}};
  sim::SimulationOptions options;
  options.sample_rate_hz = c.rate_hz;
  options.site = TestSite();
  options.perfect_sensors = true;
  auto run = sim::Simulate(sim::SimulatedUnit{}, profile, options);
  ASSERT_TRUE(run.ok()) << run.status();
  const DriftExtremes drift = FreeInertialDrift(run->run, 1e9, /*hold_vertical=*/true);
  std::printf("%.0f Hz, %.3g deg/s^2: horizontal velocity %.3g m/s, position %.3g m, attitude %.3g rad\n", c.rate_hz,
              c.acceleration_deg_s2, drift.horizontal_velocity_mps, drift.horizontal_position_m, drift.attitude_rad);
  EXPECT_LT(drift.horizontal_velocity_mps, 1e-5);
  EXPECT_LT(drift.attitude_rad, 1e-8);
}

INSTANTIATE_TEST_SUITE_P(Rates, TableRateChanges,
                         ::testing::Values(RateChange{10.0, 1e7}, RateChange{50.0, 1e7}, RateChange{100.0, 1e7},
                                           RateChange{10.0, 10.0}, RateChange{50.0, 10.0}, RateChange{100.0, 10.0}),
                         [](const auto& param_info) {
                           return std::to_string(static_cast<int>(param_info.param.rate_hz)) + "Hz_" +
                                  (param_info.param.acceleration_deg_s2 > 1e3 ? "step" : "ramp");
                         });

}  // namespace
}  // namespace insdiag::engine
