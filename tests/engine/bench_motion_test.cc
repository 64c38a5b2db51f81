// Where the bench moved against its reference (monitor/bench_motion.h): found
// where a still unit rocks, never on a still bench or a turning table whose
// unit has scale-factor errors; and the monitor holds nothing there against
// the unit.
#include "insdiag/engine/monitor/bench_motion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "insdiag/engine/monitor/innovation_tests.h"
#include "insdiag/engine/monitor/sample_screening.h"
#include "insdiag/engine/nav/table_motion.h"
#include "scenarios.h"

namespace insdiag::engine {
namespace {

using testing::kDeg;

constexpr double kAlpha = 0.01;

std::vector<BenchMotion> MotionOf(const BenchRun& run) {
  const nav::RunCompensations compensations(run);
  return FindBenchMotion(run, ReferenceMeasurements(run, compensations), 1.0, kAlpha);
}

sim::TableProfile StillProfile(double total_s) {
  sim::TableProfile p;
  p.name = "still";
  p.angular_acceleration_rad_s2 = 10.0 * kDeg;
  p.thermal.ambient_degc = 25.0;
  p.segments = {{sim::TableSegment::Kind::kHold, total_s, 0, 0, 0}};
  return p;
}

// A rocking about body x the reference does not record, from `start_s`: a
// ring-down θ(t) = A·e^(−t/τ)·sin(2πft) into the gyro x rate and the
// specific force gravity turns through body y (f_y = −g sin θ on a level unit
// whose z points down, as the bench's run reads it).
void Rock(BenchRun& run, double start_s, double amplitude_rad, double frequency_hz, double decay_s) {
  const double g = 9.80665;
  const double w = 2.0 * std::numbers::pi * frequency_hz;
  for (ImuSample& s : run.samples) {
    const double t = s.t_s - start_s;
    if (t < 0.0) continue;
    const double envelope = amplitude_rad * std::exp(-t / decay_s);
    const double angle = envelope * std::sin(w * t);
    const double rate = envelope * (w * std::cos(w * t) - std::sin(w * t) / decay_s);
    s.gyro_rad_s.x() += rate;
    s.acc_mps2.y() += g * std::sin(angle);
  }
}

// Over 10 seeds of a still navigation-grade unit, a family-wise 1 % test
// flags a run with probability ≤ 0.01: two or more flagged runs happen with
// probability < 0.5 %; a rule that flagged quantised or Gaussian noise as
// motion would flag most of them.
TEST(BenchMotion, NoneOnAStillBench) {
  int flagged = 0;
  for (uint64_t seed = 1; seed <= 10; ++seed) {
    const auto sim = testing::SimulateOrDie(testing::NavigationGradeUnit(), StillProfile(600.0), 100.0, seed);
    flagged += MotionOf(sim.run).empty() ? 0 : 1;
  }
  EXPECT_LE(flagged, 1);
}

// A turning table's reference holds its motion; a unit whose scale factors
// and misalignments are 1000 ppm and 1 mrad reads the table's accelerations
// wrongly by less than its noise within an update, and nothing is flagged.
TEST(BenchMotion, NoneOnATurningTableWithScaleFactorErrors) {
  sim::SimulatedUnit unit = testing::NavigationGradeUnit();
  for (const char* spec : {"gyro_scale_factor=1e-3", "gyro_misalignment=1e-3", "acc_scale_factor=1e-3"}) {
    auto effects = sim::ParseTrueEffect(spec);
    ASSERT_TRUE(effects.ok()) << effects.status();
    unit.effects.insert(unit.effects.end(), effects->begin(), effects->end());
  }
  int flagged = 0;
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    const auto sim = testing::SimulateOrDie(unit, testing::ShortTurnsProfile(120.0, 900.0), 100.0, seed);
    flagged += MotionOf(sim.run).empty() ? 0 : 1;
  }
  EXPECT_LE(flagged, 1);
}

// A knock at 200 s that rings down (0.5 mrad at 3 Hz, τ 2 s): found from its
// start, for as long as the ring-down stands above the gyro's noise, and
// nowhere else.
TEST(BenchMotion, FindsARingDownWhereItIs) {
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    auto sim = testing::SimulateOrDie(testing::NavigationGradeUnit(), StillProfile(600.0), 100.0, seed);
    Rock(sim.run, 200.0, 0.5e-3, 3.0, 2.0);
    const std::vector<BenchMotion> motion = MotionOf(sim.run);
    ASSERT_FALSE(motion.empty()) << "seed " << seed;
    EXPECT_LE(motion.front().start_s, 200.0) << "seed " << seed;
    EXPECT_GE(motion.front().end_s, 205.0) << "seed " << seed;
    EXPECT_LE(motion.back().end_s, 240.0) << "seed " << seed;
    EXPECT_GE(motion.front().start_s, 198.0) << "seed " << seed;
    EXPECT_TRUE(BenchMovedWithin(motion, 200.5, 201.5));
    EXPECT_FALSE(BenchMovedWithin(motion, 100.0, 101.0));
  }
}

// A stretch holds the instants after its start up to its end, as the
// interval ending at each.
TEST(BenchMotion, AnInstantIsInsideAStretchFromJustAfterItsStartToItsEnd) {
  std::vector<BenchMotion> motion(2);
  motion[0].start_s = 10.0;
  motion[0].end_s = 12.0;
  motion[1].start_s = 30.0;
  motion[1].end_s = 30.5;
  for (double t : {10.0, 9.0, 12.000001, 20.0, 30.0, 31.0}) {
    EXPECT_FALSE(BenchMovedAt(motion, t)) << t;
    EXPECT_EQ(BenchMovedAt(motion, t), BenchMovedWithin(motion, std::nextafter(t, -1.0e300), t)) << t;
  }
  for (double t : {10.000001, 11.0, 12.0, 30.25, 30.5}) {
    EXPECT_TRUE(BenchMovedAt(motion, t)) << t;
    EXPECT_EQ(BenchMovedAt(motion, t), BenchMovedWithin(motion, std::nextafter(t, -1.0e300), t)) << t;
  }
  EXPECT_FALSE(BenchMovedAt({}, 1.0));
}

// An update at which the bench moved is neither an outlier nor a window's
// evidence: a burst of wild innovations there leaves no interval, and the
// same burst where the bench held is an outlier and a gradual failure.
TEST(BenchMotion, TheMonitorHoldsNothingThereAgainstTheUnit) {
  MonitorOptions options;
  for (const bool bench_moved : {true, false}) {
    InnovationTests tests(600, 1.0, options);
    std::mt19937_64 rng(7);
    std::normal_distribution<double> normal;
    for (int k = 0; k < 600; ++k) {
      const bool burst = k >= 100 && k < 130;
      InnovationTests::PerChannel nu{}, S{};
      for (int c = 0; c < kChannelCount; ++c) {
        S[static_cast<size_t>(c)] = 1.0;
        nu[static_cast<size_t>(c)] = (burst ? 8.0 : 1.0) * normal(rng);
      }
      tests.Add(k, k + 1.0, nu, S, !(burst && bench_moved));
    }
    EXPECT_EQ(tests.faults().empty(), bench_moved);
    EXPECT_EQ(tests.gradual_found(), !bench_moved);
  }
}

}  // namespace
}  // namespace insdiag::engine
