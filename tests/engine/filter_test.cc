// The estimator against simulated truth: statistical consistency of the
// forward filter and smoother with the true model, numerical robustness over
// hours, and the seed's monitoring of faults.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cmath>

#include "insdiag/engine/filter/forward_filter.h"
#include "insdiag/engine/filter/smoother.h"
#include "insdiag/engine/stats/distributions.h"
#include "scenarios.h"

namespace insdiag::engine {
namespace {

using testing::kDeg;
using testing::kDegPerHour;

// The drift truth aligned with epoch k: the filter's sensor state at an epoch
// is the value the next sample will see.
Eigen::Matrix<double, 6, 1> TrueDrifts(const sim::SimulatedRun& sim, const ForwardPass& fw, int k) {
  const size_t j = std::min(static_cast<size_t>(fw.epoch_sample[static_cast<size_t>(k)]) + 1, sim.truth.size() - 1);
  Eigen::Matrix<double, 6, 1> d;
  d << sim.truth[j].gyro_gm, sim.truth[j].acc_gm;
  return d;
}

double FractionWithinThreeSigma(const sim::SimulatedRun& sim, const ForwardPass& fw, const SmoothedPass& sm,
                                const StateLayout& layout) {
  int inside = 0, total = 0;
  for (int k = 0; k < fw.epochs(); ++k) {
    const auto truth = TrueDrifts(sim, fw, k);
    for (int i = 0; i < 6; ++i) {
      const int s = layout.gyro_bias() + i;
      inside += std::abs(sm.x(k, s) - truth[i]) <= 3.0 * std::sqrt(sm.variance(k, s)) ? 1 : 0;
      ++total;
    }
  }
  return static_cast<double>(inside) / total;
}

struct ConsistencyCase {
  std::string profile;
  uint64_t seed;
};

class TrueModelConsistency : public ::testing::TestWithParam<ConsistencyCase> {};

TEST_P(TrueModelConsistency, NisInItsBandAndSmoothedDriftsWithinThreeSigma) {
  const auto unit = testing::NavigationGradeUnit();
  const auto sim = testing::SimulateOrDie(unit, testing::BuiltinProfileOrDie(GetParam().profile), 50.0, GetParam().seed);
  AnalysisOptions options;
  auto analysis = Analyze(sim.run, {}, options);
  ASSERT_TRUE(analysis.ok()) << analysis.status();
  const AnalysisReport& r = analysis->report;
  // The mean of N χ²(1) values lies in [χ²_N(α/2), χ²_N(1 − α/2)]/N with probability 1 − α.
  const int n = r.scalar_updates;
  EXPECT_GT(r.fit.nis_mean, stats::ChiSquareQuantile(0.0005, n) / n);
  EXPECT_LT(r.fit.nis_mean, stats::ChiSquareQuantile(0.9995, n) / n);
  for (const ChannelFit& c : r.channels) {
    if (c.count == 0) continue;  // the attitude of a run whose encoders are not read: nothing to fit
    const double low = stats::ChiSquareQuantile(0.001 / 2, c.count) / c.count;
    const double high = stats::ChiSquareQuantile(1 - 0.001 / 2, c.count) / c.count;
    EXPECT_GT(c.nis_mean, low) << c.name;
    EXPECT_LT(c.nis_mean, high) << c.name;
    EXPECT_GT(c.whiteness_p_value, 0.001) << c.name;
  }
  EXPECT_EQ(r.verdict, Verdict::kGood);
  EXPECT_TRUE(r.faults.empty());

  const ErrorModel model = testing::TrueBaseModel(unit);
  auto fw = RunForwardFilter(sim.run, model, options.filter);
  ASSERT_TRUE(fw.ok());
  auto sm = RunSmoother(*fw);
  ASSERT_TRUE(sm.ok());
  EXPECT_GE(FractionWithinThreeSigma(sim, *fw, *sm, StateLayout(model)), 0.99);
}

INSTANTIATE_TEST_SUITE_P(Profiles, TrueModelConsistency,
                         ::testing::Values(ConsistencyCase{"static", 11}, ConsistencyCase{"rotations", 12}),
                         [](const auto& param_info) { return param_info.param.profile; });

TEST(TrueModelConsistency, SensorStateNeesIsInsideItsChiSquareBandOverSeeds) {
  // Independent runs: Σ over seeds of the drift states' NEES at one epoch is
  // χ²(6 · seeds) when the filter's and smoother's covariances are right.
  const auto unit = testing::NavigationGradeUnit();
  const ErrorModel model = testing::TrueBaseModel(unit);
  const StateLayout layout(model);
  const auto profile = testing::ShortTurnsProfile(300.0, 1200.0);
  constexpr int kSeeds = 20;
  double forward_nees = 0.0, smoothed_nees = 0.0;
  for (int seed = 0; seed < kSeeds; ++seed) {
    const auto sim = testing::SimulateOrDie(unit, profile, 50.0, 100 + static_cast<uint64_t>(seed));
    auto fw = RunForwardFilter(sim.run, model, FilterOptions{});
    ASSERT_TRUE(fw.ok());
    SmootherOptions smoother_options;
    smoother_options.block_begin = layout.gyro_bias();
    smoother_options.block_size = 6;
    auto sm = RunSmoother(*fw, smoother_options);
    ASSERT_TRUE(sm.ok());
    const int k = fw->epochs() / 2;
    const Eigen::Matrix<double, 6, 1> truth = TrueDrifts(sim, *fw, k);
    Eigen::MatrixXd Pf, Ps;
    UnpackSymmetric(fw->P_filt.row(k).data(), fw->state_size, Pf);
    UnpackSymmetric(sm->block_covariance.row(k).data(), 6, Ps);
    const Eigen::VectorXd ef = fw->x_filt.row(k).segment(layout.gyro_bias(), 6).transpose() - truth;
    const Eigen::VectorXd es = sm->x.row(k).segment(layout.gyro_bias(), 6).transpose() - truth;
    forward_nees += ef.dot(Pf.block(layout.gyro_bias(), layout.gyro_bias(), 6, 6).ldlt().solve(ef));
    smoothed_nees += es.dot(Ps.ldlt().solve(es));
  }
  const double dof = 6.0 * kSeeds;
  const double low = stats::ChiSquareQuantile(0.005, dof);
  const double high = stats::ChiSquareQuantile(0.995, dof);
  EXPECT_GT(forward_nees, low);
  EXPECT_LT(forward_nees, high);
  EXPECT_GT(smoothed_nees, low);
  EXPECT_LT(smoothed_nees, high);
}

// A still table sampled at 1 Hz, at the default one-second update: an
// interval of one sample, where the position and velocity innovations are multiples of
// one another against the exact reference (epoch_run.h, UpdateIntervalForRun).
// The filter updates every two samples, and the true model's innovations
// fill every channel's χ² band over seeds (before: the velocity channels'
// NIS were near zero and the positions' half).
TEST(TrueModelConsistency, EveryChannelsNisIsInsideItsBandForARunOfOneSampleASecond) {
  const auto unit = testing::NavigationGradeUnit();
  const ErrorModel model = testing::TrueBaseModel(unit);
  const auto profile = testing::BuiltinProfileOrDie("static");
  std::array<double, kChannelCount> normalised_squares{};
  std::array<int, kChannelCount> updates{};
  for (int seed = 0; seed < 4; ++seed) {
    auto sim = testing::SimulateOrDie(unit, profile, 1.0, 300 + static_cast<uint64_t>(seed));
    sim.run.metadata.DeclareAttitudeReadout(true);
    auto fw = RunForwardFilter(sim.run, model, FilterOptions{});
    ASSERT_TRUE(fw.ok()) << fw.status();
    ASSERT_GT(fw->epochs(), 2);
    EXPECT_EQ(fw->epoch_sample[2] - fw->epoch_sample[1], kMinimumSamplesPerUpdate);
    for (int k = 0; k < fw->epochs(); ++k) {
      for (int c = 0; c < kChannelCount; ++c) {
        if (!fw->Observed(k, c)) continue;
        normalised_squares[static_cast<size_t>(c)] +=
            fw->innovation(k, c) * fw->innovation(k, c) / fw->innovation_variance(k, c);
        ++updates[static_cast<size_t>(c)];
      }
    }
  }
  for (int c = 0; c < kChannelCount; ++c) {
    const int n = updates[static_cast<size_t>(c)];
    // A static table stands still throughout: every channel, the attitude's too, is observed.
    ASSERT_GT(n, 0) << kChannelNames[static_cast<size_t>(c)];
    const double nis = normalised_squares[static_cast<size_t>(c)] / n;
    EXPECT_GT(nis, stats::ChiSquareQuantile(0.0005, n) / n) << kChannelNames[static_cast<size_t>(c)];
    EXPECT_LT(nis, stats::ChiSquareQuantile(0.9995, n) / n) << kChannelNames[static_cast<size_t>(c)];
  }
}

// The 2×2 moments the second-order M-step reads (SmootherOptions::pair_states)
// are the smoother's own: the pair's block of P_{k|K} and, off the diagonal
// too, Cov(x_{k+1}, x_k | all data) — checked against the block covariance
// and the per-state lag-one covariance on two neighbouring drift states.
TEST(Smoother, PairMomentsAreTheSmoothedBlockAndLagOneCovariances) {
  const auto unit = testing::NavigationGradeUnit();
  const ErrorModel model = testing::TrueBaseModel(unit);
  const StateLayout layout(model);
  const auto sim = testing::SimulateOrDie(unit, testing::ShortTurnsProfile(300.0, 600.0), 50.0, 5);
  auto fw = RunForwardFilter(sim.run, model, FilterOptions{});
  ASSERT_TRUE(fw.ok());
  SmootherOptions options;
  options.block_begin = layout.gyro_bias();
  options.block_size = 2;
  options.pair_states = {layout.gyro_bias()};
  auto sm = RunSmoother(*fw, options);
  ASSERT_TRUE(sm.ok());
  ASSERT_EQ(sm->pair_moments.size(), 1u);
  const auto& m = sm->pair_moments.front();
  const int i = layout.gyro_bias();
  for (int k = 0; k < fw->epochs(); ++k) {
    Eigen::MatrixXd block;
    UnpackSymmetric(sm->block_covariance.row(k).data(), 2, block);
    EXPECT_DOUBLE_EQ(m(k, 0), block(0, 0));
    EXPECT_DOUBLE_EQ(m(k, 1), block(0, 1));
    EXPECT_DOUBLE_EQ(m(k, 2), block(1, 1));
    EXPECT_DOUBLE_EQ(m(k, 3), sm->lag_one_covariance(k, i));
    EXPECT_DOUBLE_EQ(m(k, 6), sm->lag_one_covariance(k, i + 1));
  }
  // The lag-one cross terms are not zero: the two gyro drifts are coupled through the attitude.
  EXPECT_GT(m.col(4).cwiseAbs().maxCoeff(), 0.0);
  // A pair that leaves the state is refused.
  options.pair_states = {fw->state_size - 1};
  EXPECT_FALSE(RunSmoother(*fw, options).ok());
}

TEST(Robustness, FourHourRunKeepsTheCovarianceSymmetricPositiveDefinite) {
  // Four hours: the full profile twice, then still to the four-hour mark, at 20 Hz.
  auto profile = testing::BuiltinProfileOrDie("full");
  const auto segments = profile.segments;
  profile.segments.insert(profile.segments.end(), segments.begin(), segments.end());
  const double so_far = sim::TableMotion::Compile(profile)->DurationS();
  profile.segments.push_back({sim::TableSegment::Kind::kHold, 4.0 * 3600.0 - so_far, 0, 0, 0});
  const auto unit = testing::NavigationGradeUnit();
  const auto sim = testing::SimulateOrDie(unit, profile, 20.0, 21);
  ASSERT_GT(sim.run.DurationS(), 4.0 * 3600.0 - 1.0);
  auto fw = RunForwardFilter(sim.run, testing::TrueBaseModel(unit), FilterOptions{});
  ASSERT_TRUE(fw.ok()) << fw.status();
  Eigen::MatrixXd P;
  for (int k = 0; k < fw->epochs(); ++k) {
    UnpackSymmetric(fw->P_filt.row(k).data(), fw->state_size, P);
    // Jacobi-scaled so that the test is about correlations, not units.
    const Eigen::VectorXd d = P.diagonal().cwiseSqrt().cwiseInverse();
    const Eigen::LLT<Eigen::MatrixXd> llt(d.asDiagonal() * P * d.asDiagonal());
    ASSERT_EQ(llt.info(), Eigen::Success) << "not positive definite at epoch " << k;
    ASSERT_GT(P.diagonal().minCoeff(), 0.0) << "epoch " << k;
  }
  auto sm = RunSmoother(*fw);
  ASSERT_TRUE(sm.ok()) << sm.status();
  EXPECT_GT(sm->variance.minCoeff(), 0.0);
  // No divergence: the innovations stay consistent with their predicted variance to the end.
  const int K = fw->epochs();
  double late_nis = 0.0;
  int late = 0;
  for (int k = 3 * K / 4; k < K; ++k) {
    for (int c = 0; c < kChannelCount; ++c) {
      if (!fw->Observed(k, c)) continue;
      late_nis += fw->innovation(k, c) * fw->innovation(k, c) / fw->innovation_variance(k, c);
      ++late;
    }
  }
  EXPECT_GT(late_nis / late, stats::ChiSquareQuantile(0.0005, late) / late);
  EXPECT_LT(late_nis / late, stats::ChiSquareQuantile(0.9995, late) / late);
}

// A still table with the inner axis at `inner_deg`, `duration_s` long. At 0°
// gyros x and y are level (a drift on either tilts the unit its own way); at
// 90° body x is vertical and z points north.
sim::TableProfile StillProfile(double inner_deg, double duration_s) {
  sim::TableProfile p;
  p.name = "still";
  p.angular_acceleration_rad_s2 = 10.0 * kDeg;
  p.initial_inner_rad = inner_deg * kDeg;
  p.thermal.ambient_degc = 25.0;
  p.segments = {{sim::TableSegment::Kind::kHold, duration_s, 0, 0, 0}};
  return p;
}

class GyroBiasStep : public ::testing::TestWithParam<int> {};

TEST_P(GyroBiasStep, IsFlaggedWithinAMinuteAndLocalisedToItsGyro) {
  const int axis = GetParam();
  auto unit = testing::NavigationGradeUnit();
  constexpr double kStepTime = 1200.0;
  // A failing DTG whose drift jumps by 1°/h (a hundred times its drift σ). A
  // step of 0.1°/h tilts the unit by less than its angle random walk does in
  // a second, and takes minutes, not seconds, to tell from it.
  unit.bias_steps.push_back({Sensor::kGyro, axis, kStepTime, 1.0 * kDegPerHour});
  const double inner_deg = axis == 2 ? 90.0 : 0.0;  // the gyro under test lies level
  const auto sim =
      testing::SimulateOrDie(unit, StillProfile(inner_deg, 2400.0), 50.0, 31 + static_cast<uint64_t>(axis));
  auto analysis = Analyze(sim.run, {}, AnalysisOptions{});
  ASSERT_TRUE(analysis.ok()) << analysis.status();
  const AnalysisReport& r = analysis->report;
  EXPECT_NE(r.verdict, Verdict::kGood);
  // Flagged: the first fault interval after the step begins within 60 s of it.
  const auto first = std::find_if(r.faults.begin(), r.faults.end(),
                                  [&](const FaultInterval& f) { return f.end_s >= kStepTime; });
  ASSERT_NE(first, r.faults.end()) << "no fault interval after the step";
  EXPECT_LE(std::max(first->start_s, kStepTime), kStepTime + 60.0);
  // Nothing flagged well before the step.
  for (const FaultInterval& f : r.faults) EXPECT_GT(f.end_s, kStepTime - 120.0) << f.channel;
  // Localised: the most discrepant sensor state is that gyro's drift, near the step.
  ASSERT_FALSE(r.localisation.empty());
  const Localisation& where = r.localisation.front();
  EXPECT_EQ(where.state, std::string("gyro_bias_gm.") + "xyz"[axis]);
  EXPECT_EQ(where.method, "JUMP");
  EXPECT_NEAR(where.time_s, kStepTime, 30.0);
  // The jump's size, to within its uncertainty and the onset's one-epoch resolution.
  EXPECT_NEAR(where.jump, 1.0 * kDegPerHour, 3.0 * where.jump_std_error + 0.1 * kDegPerHour)
      << "σ " << where.jump_std_error;
}

INSTANTIATE_TEST_SUITE_P(Axes, GyroBiasStep, ::testing::Values(0, 1, 2),
                         [](const auto& param_info) { return std::string(1, "xyz"[param_info.param]); });

TEST(Spikes, AreFlaggedAsOutliersAndDoNotCorruptTheEstimatesAfterThem) {
  auto unit = testing::NavigationGradeUnit();
  // Transmission errors: single samples off by hundreds of noise σ.
  unit.spikes = {{Sensor::kGyro, 0, 600.005, 2e-3},
                 {Sensor::kAccelerometer, 1, 900.005, 0.5},
                 {Sensor::kGyro, 2, 1500.005, -3e-3},
                 {Sensor::kAccelerometer, 2, 1800.005, -0.8}};
  const auto sim = testing::SimulateOrDie(unit, testing::ShortTurnsProfile(600.0, 2400.0), 50.0, 41);
  auto analysis = Analyze(sim.run, {}, AnalysisOptions{});
  ASSERT_TRUE(analysis.ok()) << analysis.status();
  const AnalysisReport& r = analysis->report;
  for (const auto& spike : unit.spikes) {
    const std::string channel = std::string(spike.sensor == Sensor::kGyro ? "gyro_" : "acc_") + "xyz"[spike.axis];
    const bool flagged = std::any_of(r.faults.begin(), r.faults.end(), [&](const FaultInterval& f) {
      return f.channel == channel && f.kind == FaultKind::kOutlier && std::abs(f.start_s - spike.time_s) < 0.05;
    });
    EXPECT_TRUE(flagged) << channel << " at " << spike.time_s;
  }
  // Only those four: no false alarms elsewhere, and no gradual failure.
  EXPECT_EQ(r.faults.size(), unit.spikes.size());
  EXPECT_EQ(r.verdict, Verdict::kOperable);
  EXPECT_GT(r.fit.nis_mean, r.nis_band_low);
  EXPECT_LT(r.fit.nis_mean, r.nis_band_high);

  // The estimates after the spikes stay with the truth.
  const ErrorModel model = testing::TrueBaseModel(unit);
  BenchRun repaired = sim.run;
  ScreenAndRepairSpikes(repaired, AnalysisOptions{}.screening);
  auto fw = RunForwardFilter(repaired, model, FilterOptions{});
  ASSERT_TRUE(fw.ok());
  auto sm = RunSmoother(*fw);
  ASSERT_TRUE(sm.ok());
  EXPECT_GE(FractionWithinThreeSigma(sim, *fw, *sm, StateLayout(model)), 0.99);
}

}  // namespace
}  // namespace insdiag::engine
