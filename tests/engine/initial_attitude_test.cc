// What a run says of its start reaches the filter and the excitation checks:
// the initial attitude's covariance from the run's stated accuracy (level,
// heading, or a heading the bench did not survey), and what the table did
// read from its reference attitude, not from the sensors.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <string>

#include "insdiag/engine/filter/epoch_run.h"
#include "insdiag/engine/filter/forward_filter.h"
#include "insdiag/engine/finder/effect_finder.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/model/state_layout.h"
#include "insdiag/engine/nav/wgs84.h"
#include "scenarios.h"

namespace insdiag::engine {
namespace {

using testing::kDeg;
using testing::kDegPerHour;

Eigen::Vector3d AttitudeSigmaRad(const ErrorModel& model, const EpochRun& run) {
  const StateLayout layout(model);
  const Eigen::MatrixXd P = InitialCovariance(model, layout, run);
  return P.diagonal().segment<3>(layout.attitude()).cwiseSqrt();
}

TEST(InitialAttitude, TakesTheRunsStatedLevelAndHeadingElseTheEncoders) {
  const ErrorModel model = testing::TrueBaseModel(testing::NavigationGradeUnit());
  EpochRun run;
  run.site = testing::TestSite();
  const double encoders_rad = model.reference.attitude_sigma_rad;
  EXPECT_TRUE(AttitudeSigmaRad(model, run).isApprox(Eigen::Vector3d::Constant(encoders_rad)));

  run.stated_attitude.level_sigma_rad = 1e-3;
  run.stated_attitude.heading_sigma_rad = 2e-3;
  EXPECT_TRUE(AttitudeSigmaRad(model, run).isApprox(Eigen::Vector3d(1e-3, 1e-3, 2e-3)));
}

// A heading the bench did not survey is known as well as gyro-compassing
// the start tells it: the largest drift σ over Ω cos L, and never beyond the
// phi-angle model's range.
TEST(InitialAttitude, AnUnsurveyedHeadingIsAsUncertainAsGyroCompassingLeavesIt) {
  ErrorModel model = testing::TrueBaseModel(testing::NavigationGradeUnit());
  EpochRun run;
  run.site = testing::TestSite();
  run.stated_attitude.heading_surveyed = false;
  for (auto& axis : model.gyro.bias) axis.sigma = 0.01 * kDegPerHour;
  const double horizontal_earth_rate = wgs84::kEarthRateRadS * std::cos(run.site.latitude_rad);
  EXPECT_NEAR(AttitudeSigmaRad(model, run).z(), 0.01 * kDegPerHour / horizontal_earth_rate, 1e-12);
  // A consumer gyro: the heading is not told; the bound holds.
  for (auto& axis : model.gyro.bias) axis.sigma = 0.1 * kDeg;
  EXPECT_EQ(AttitudeSigmaRad(model, run).z(), kUnsurveyedHeadingLimitRad);
}

// A unit at rest with a consumer gyro's turn-on bias (0.4 °/s, hundreds of
// Earth rates) and noise: the table did not turn it, so nothing that needs
// rotation or tilts is excited, however much the gyros read.
TEST(RunExcitation, ComesFromTheTablesMotionNotFromTheSensorsBiasOrNoise) {
  BenchRun run;
  run.metadata.site = testing::TestSite();
  std::mt19937_64 rng(62);
  std::normal_distribution<double> noise(0.0, 0.05 * kDeg);
  for (int k = 1; k <= 100000; ++k) {
    ImuSample s;
    s.t_s = 0.01 * k;
    s.gyro_rad_s = Eigen::Vector3d(0.4 * kDeg + noise(rng), -0.4 * kDeg + noise(rng), 0.3 * kDeg + noise(rng));
    s.acc_mps2 = Eigen::Vector3d(0.0, 0.0, -9.81);
    run.samples.push_back(s);
  }
  const RunExcitation still = MeasureExcitation(run);
  EXPECT_EQ(still.turned_rad, Eigen::Vector3d::Zero());
  EXPECT_EQ(still.force_range_mps2, Eigen::Vector3d::Zero());
  std::string why;
  EXPECT_FALSE(Excites(still, EffectTerm{FindEffectFamily("gyro_scale_factor"), 0, 0}, ExcitationThresholds{}, 9.81,
                       &why));
  EXPECT_EQ(why, "the run does not turn the unit about its x axis");

  // The same samples with the table turning the body about z, one turn
  // every 100 s: ten turns about z (less the last stride the check skips,
  // every tenth sample is read), none about x or y.
  for (ImuSample& s : run.samples) s.ref_rpy_rad.z() = std::remainder(2.0 * std::numbers::pi * s.t_s / 100.0, 2.0 * std::numbers::pi);
  const RunExcitation turning = MeasureExcitation(run);
  EXPECT_NEAR(turning.turned_rad.z(), 2.0 * std::numbers::pi * (999.91 - 0.01) / 100.0, 1e-6);
  EXPECT_NEAR(turning.turned_rad.x(), 0.0, 1e-9);
  EXPECT_TRUE(Excites(turning, EffectTerm{FindEffectFamily("gyro_scale_factor"), 2, 2}, ExcitationThresholds{}, 9.81,
                      &why));
}

}  // namespace
}  // namespace insdiag::engine
