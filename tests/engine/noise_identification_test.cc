// The identification's noise terms (analysis/noise_identification.h): the
// terms the Allan fit left at bounds re-tuned by maximum likelihood, and the
// bench's reference noise fitted where the innovations reject its accuracy.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "insdiag/benchrun/bench_run_csv.h"
#include "insdiag/engine/analysis.h"
#include "insdiag/engine/filter/epoch_run.h"
#include "insdiag/engine/ident/retarget.h"
#include "insdiag/engine/nav/rotation.h"
#include "scenarios.h"
#include "support/monte_carlo.h"

namespace insdiag::engine::ident {
namespace {

// NoiseRetuneTest.RealRecordNisNearOne, the re-tuning on the real record, is in
// real_records_test.cc, beside the other test that analyses that record.

// The maximum-likelihood re-tuning of noise terms set from Allan bounds
// (retarget.h), on simulated runs of known truth: the white densities of
// gyros and accelerometers start at four times the truth, as an Allan curve
// whose short-τ end is buried under quantisation bounds them; the re-tuned
// densities must cover the truth in their 95% intervals (ln ŝ ± 1.96 SE).
// Two groups a seed; at 95 % each, the threshold fails falsely with
// probability ≤ 1.2 % (the sweep's 5 seeds: 8 of 10 checks). The suite runs
// 3 seeds: at least 4 of 6, which catches a coverage of 50 % with
// probability 0.66 (five seeds: 0.95).
TEST(NoiseRetuneTest, RecoversKnownWhiteDensitiesFromTheirBoundsOverSeeds) {
  const int kSeeds = insdiag::testing::Runs({.suite = 3, .sweep = 5});
  constexpr double kBoundOverTruth = 4.0;
  const sim::SimulatedUnit unit = testing::NavigationGradeUnit();
  const ErrorModel truth = testing::TrueBaseModel(unit);
  ErrorModel bound = truth;
  for (int i = 0; i < 3; ++i) {
    bound.gyro.white_noise_density[i] *= kBoundOverTruth;
    bound.acc.white_noise_density[i] *= kBoundOverTruth;
  }
  UnresolvedNoise which;
  which.gyro_white = {true, true, true};
  which.acc_white = {true, true, true};
  int checks = 0, covered = 0;
  for (int seed = 0; seed < kSeeds; ++seed) {
    const sim::SimulatedRun s =
        testing::SimulateOrDie(unit, testing::BuiltinProfileOrDie("rotations"), 10.0, 700 + seed);
    const auto epochs = CondenseRun(s.run, bound, FilterOptions{}.update_interval_s);
    ASSERT_TRUE(epochs.ok()) << epochs.status();
    auto scaled = ScaleUnresolvedNoise(*epochs, bound, which);
    ASSERT_TRUE(scaled.ok()) << scaled.status();
    for (const NoiseScaleGroup& g : scaled->groups) {
      const double true_scale = 1.0 / kBoundOverTruth;
      const double z = std::abs(std::log(g.scale / true_scale)) / g.log_std_error;
      std::printf("seed %d %-12s scale %.4f (truth %.4f), SE of ln %.3f, z %.2f%s\n", 700 + seed,
                  g.name.c_str(), g.scale, true_scale, g.log_std_error, z,
                  g.at_limit ? " (at limit)" : "");
      EXPECT_FALSE(g.at_limit) << g.name;
      ++checks;
      covered += z <= 1.96;
    }
  }
  EXPECT_EQ(checks, 2 * kSeeds);
  const int least = insdiag::testing::LeastSuccesses(checks, 0.95, 0.012);
  std::printf("white densities: %d of %d intervals cover the truth (at least %d)\n", covered, checks, least);
  ASSERT_GT(least, 0);
  EXPECT_GE(covered, least) << covered << " of " << checks << " intervals cover the truth";
}

// A bench that sways: the unit's position wanders about the reference by
// `sway_m` along each NED axis, drawn afresh every second and cosine-interpolated in
// between, so that it is at rest at each whole second (the filter's update
// instants see white position noise of that σ and no velocity) and its
// acceleration is smooth. The accelerometers sense that acceleration: each
// sample's mean, v(t_k) − v(t_{k−1}) over the interval, in the body frame.
void AddSway(BenchRun& run, const Eigen::Vector3d& sway_m, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const double t0 = run.samples.front().t_s;
  const auto knots = static_cast<size_t>(run.DurationS()) + 2;
  std::vector<Eigen::Vector3d> position_m(knots);
  for (auto& p : position_m) p = sway_m.cwiseProduct(Eigen::Vector3d(normal(rng), normal(rng), normal(rng)));
  // d(t) = d_j (1 + cos πu)/2 + d_{j+1} (1 − cos πu)/2, u = t − j: v = (d_{j+1} − d_j) (π/2) sin
  // πu.
  const auto velocity_at = [&](double t) {
    const double elapsed = t - t0;
    const auto j = std::min(static_cast<size_t>(std::floor(elapsed)), knots - 2);
    const double u = elapsed - static_cast<double>(j);
    return Eigen::Vector3d((position_m[j + 1] - position_m[j]) * (std::numbers::pi / 2.0) *
                           std::sin(std::numbers::pi * u));
  };
  for (size_t k = 1; k < run.samples.size(); ++k) {
    ImuSample& s = run.samples[k];
    const double dt = s.t_s - run.samples[k - 1].t_s;
    const Eigen::Vector3d acceleration_n =
        (velocity_at(s.t_s) - velocity_at(run.samples[k - 1].t_s)) / dt;
    s.acc_mps2 += nav::EulerToDcm(s.ref_rpy_rad).transpose() * acceleration_n;
  }
}

bool SaysTheReferenceNoiseWasRaised(const AnalysisReport& report) {
  return std::any_of(report.decisions.begin(), report.decisions.end(), [](const Decision& d) {
    return d.kind == DecisionKind::kReferenceNoiseRaised && d.adopted;
  });
}

// The reference noise is raised where the innovations exceed their
// predicted variance, to its maximum-likelihood value, and only where the
// likelihood rejects the bench's stated accuracy (analysis/noise_identification.cc),
// across and along the vertical apart. A unit on a bench that sways by 1 mm
// along every axis gets both position σ raised to that within 30 %
// (covariance matching alone gave 1.45–1.9 mm on these runs); one that moves
// by 1 mm only along the vertical, as a floor or a suspension moves it, gets
// its vertical σ raised and keeps the bench's horizontal accuracy; the same
// unit on a steady bench keeps the bench's accuracy and is not FAULTY. A
// claim on every run: one seed each way in the suite, three in the sweep.
// The swaying runs' verdict is not asserted: the static segments' Allan fit
// reads the sway's acceleration (0.5 mg at 1 Hz) as accelerometer white
// noise, 7–12 × the unit's, which the filter then expects in the velocities
// (docs/IDENTIFICATION.md).
TEST(ReferenceNoiseTest, ABenchThatSwaysHasItsReferenceNoiseMeasuredAndASteadyOneKeepsItsAccuracy) {
  constexpr double kSwayM = 1e-3;
  const ReferenceAccuracy bench = AnalysisOptions{}.reference;
  sim::TableProfile still;
  still.name = "still";
  still.angular_acceleration_rad_s2 = 10.0 * testing::kDeg;
  still.thermal.ambient_degc = 25.0;
  still.segments = {{sim::TableSegment::Kind::kHold, 1800.0, 0, 0, 0}};
  enum class Bench { kSteady, kSwaying, kHeaving };
  const auto seeds = static_cast<std::uint64_t>(insdiag::testing::Runs({.suite = 1, .sweep = 3}));
  for (std::uint64_t seed = 1; seed <= seeds; ++seed) {
    const sim::SimulatedRun steady =
        testing::SimulateOrDie(testing::NavigationGradeUnit(), still, 10.0, 900 + seed);
    for (const Bench b : {Bench::kSteady, Bench::kSwaying, Bench::kHeaving}) {
      BenchRun run = steady.run;
      if (b == Bench::kSwaying) AddSway(run, Eigen::Vector3d::Constant(kSwayM), seed);
      if (b == Bench::kHeaving) AddSway(run, Eigen::Vector3d(0.0, 0.0, kSwayM), seed);
      auto a = Analyze(run, AnalysisRequest{}, AnalysisOptions{});
      ASSERT_TRUE(a.ok()) << a.status();
      const ReferenceAccuracy& fitted = a->model.reference;
      const std::string label =
          std::string(b == Bench::kSteady ? "steady" : b == Bench::kSwaying ? "swaying" : "heaving") + ", seed " +
          std::to_string(seed) + ": reference position σ " + std::to_string(fitted.horizontal_position_sigma_m) +
          " m across, " + std::to_string(fitted.vertical_position_sigma_m) + " m along the vertical, NIS " +
          std::to_string(a->report.fit.nis_mean);
      std::printf("%s\n", label.c_str());
      if (b == Bench::kSteady) {
        EXPECT_NE(a->report.verdict, Verdict::kFaulty) << label;
        EXPECT_FALSE(SaysTheReferenceNoiseWasRaised(a->report)) << label;
        EXPECT_EQ(fitted.horizontal_position_sigma_m, bench.horizontal_position_sigma_m) << label;
        EXPECT_EQ(fitted.vertical_position_sigma_m, bench.vertical_position_sigma_m) << label;
        continue;
      }
      EXPECT_TRUE(SaysTheReferenceNoiseWasRaised(a->report)) << label;
      EXPECT_GT(fitted.vertical_position_sigma_m, 0.7 * kSwayM) << label;
      EXPECT_LT(fitted.vertical_position_sigma_m, 1.3 * kSwayM) << label;
      if (b == Bench::kSwaying) {
        EXPECT_GT(fitted.horizontal_position_sigma_m, 0.7 * kSwayM) << label;
        EXPECT_LT(fitted.horizontal_position_sigma_m, 1.3 * kSwayM) << label;
      } else {
        EXPECT_LT(fitted.horizontal_position_sigma_m, 0.1 * kSwayM) << label;
      }
    }
  }
}

}  // namespace
}  // namespace insdiag::engine::ident
