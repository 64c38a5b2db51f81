// What a run's still start says of each sensor's bias there
// (filter/start_departure.h): a warm-up of many drift σ is measured where
// the samples put it; a start that is only noise widens the prior rarely and
// little; a bench that moves at the start is not measured.
#include "insdiag/engine/filter/start_departure.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "insdiag/engine/nav/rotation.h"
#include "insdiag/engine/nav/wgs84.h"

namespace insdiag::engine {
namespace {

constexpr double kRateHz = 100.0;
constexpr double kUpdateIntervalS = 1.0;
constexpr double kStillToleranceRad = 1e-9;

// A consumer MEMS unit's class (the MPU-6050 record in data/real): white
// noise about 0.005 °/s/√Hz and 100 µg/√Hz, drift σ of a few hundredths of a
// degree per second and a milli-g, τ some minutes.
ErrorModel MemsClassModel() {
  ErrorModel m;
  for (int i = 0; i < 3; ++i) {
    m.gyro.white_noise_density[i] = 1e-4;  // rad/√s
    m.gyro.bias[static_cast<size_t>(i)] = {1e-4, 300.0};
    m.acc.white_noise_density[i] = 1e-3;  // m/s/√s
    m.acc.bias[static_cast<size_t>(i)] = {1e-3, 300.0};
  }
  return m;
}

// A still, level unit at a site, its readings white noise about a perfect
// unit's, plus a warm-up b·e^(−t/τ) on sensor axis `warm_axis` (−1: none).
BenchRun StillRun(const ErrorModel& m, double duration_s, uint64_t seed, int warm_axis, double warm_up,
                  double warm_up_tau_s) {
  BenchRun run;
  run.metadata.site = {48.1 * std::numbers::pi / 180.0, 11.6 * std::numbers::pi / 180.0, 520.0};
  const Site& site = run.metadata.site;
  const Eigen::Vector3d rate = wgs84::EarthRateNed(site.latitude_rad);
  const Eigen::Vector3d force(0.0, 0.0, -wgs84::NormalGravityMps2(site.latitude_rad, site.height_m));
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  const double dt = 1.0 / kRateHz;
  const auto n = static_cast<size_t>(duration_s * kRateHz);
  for (size_t k = 0; k < n; ++k) {
    ImuSample s;
    s.t_s = static_cast<double>(k + 1) * dt;
    s.gyro_rad_s = rate;
    s.acc_mps2 = force;
    for (int i = 0; i < 3; ++i) {
      s.gyro_rad_s[i] += m.gyro.white_noise_density[i] / std::sqrt(dt) * normal(rng);
      s.acc_mps2[i] += m.acc.white_noise_density[i] / std::sqrt(dt) * normal(rng);
    }
    if (warm_axis >= 0) {
      const double b = warm_up * std::exp(-s.t_s / warm_up_tau_s);
      (warm_axis < 3 ? s.gyro_rad_s : s.acc_mps2)[warm_axis % 3] += b;
    }
    run.samples.push_back(s);
  }
  return run;
}

double DriftSigma(const ErrorModel& m, int axis) {
  return (axis < 3 ? m.gyro : m.acc).bias[static_cast<size_t>(axis % 3)].sigma;
}

// A warm-up of ten drift σ on each axis in turn, over 3 seeds: the drift
// state starts with at least (5σ)² there (a departure of 10σ less the window's
// mean of the decay and its noise of 1σ), and the start departure is within
// four of its standard errors of the warm-up's mean over the window less its
// mean over the run.
TEST(StartDeparture, AWarmUpOfManySigmaStartsWhereTheSamplesPutIt) {
  const ErrorModel m = MemsClassModel();
  const double duration_s = 600.0, tau_s = 60.0;
  for (int axis = 0; axis < kSensorAxisCount; ++axis) {
    const double warm_up = 10.0 * DriftSigma(m, axis);
    for (uint64_t seed = 1; seed <= 3; ++seed) {
      const BenchRun run = StillRun(m, duration_s, seed, axis, warm_up, tau_s);
      const StartDeparture start = MeasureStartDeparture(run, m, kUpdateIntervalS, kStillToleranceRad, std::nullopt);
      const auto a = static_cast<size_t>(axis);
      const double w = start.window_s[a];
      ASSERT_GT(w, 0.0) << "axis " << axis;
      const double window_mean = warm_up * tau_s / w * -std::expm1(-w / tau_s);
      const double run_mean = warm_up * tau_s / duration_s * -std::expm1(-duration_s / tau_s);
      EXPECT_NEAR(start.departure[a], window_mean - run_mean, 4.0 * start.std_error[a]) << "axis " << axis;
      EXPECT_GE(start.start_square[a], std::pow(5.0 * DriftSigma(m, axis), 2)) << "axis " << axis;
    }
  }
}

// A start of white noise alone: its departure d is N(0, s²) with s = σ (the
// window where the noise resolves one σ), so d² − s² passes σ² with
// probability P(χ²₁ > 2) = 0.157. Over 40 seeds × 6 axes (240 draws, SD of
// the share 0.023) the share stays below 0.25 (4 SD), and no axis starts
// beyond (4σ)² (d beyond √17 s: p 4e-5 a draw, 0.9 % over all of them). A
// rule that took every start's departure at face value would pass σ² in
// about half the draws.
TEST(StartDeparture, AStartOfNoiseAloneWidensThePriorRarelyAndLittle) {
  const ErrorModel m = MemsClassModel();
  int widened = 0, draws = 0;
  for (uint64_t seed = 1; seed <= 40; ++seed) {
    const BenchRun run = StillRun(m, 120.0, seed, -1, 0.0, 1.0);
    const StartDeparture start = MeasureStartDeparture(run, m, kUpdateIntervalS, kStillToleranceRad, std::nullopt);
    for (int axis = 0; axis < kSensorAxisCount; ++axis) {
      const double sigma2 = std::pow(DriftSigma(m, axis), 2);
      const double square = start.start_square[static_cast<size_t>(axis)];
      widened += square > sigma2 ? 1 : 0;
      ++draws;
      EXPECT_LT(square, 16.0 * sigma2) << "seed " << seed << " axis " << axis;
    }
  }
  EXPECT_LT(static_cast<double>(widened) / draws, 0.25) << widened << " of " << draws;
}

// Where the bench moves from the first seconds, the start measures the
// bench: no axis is measured, whatever its departure.
TEST(StartDeparture, NoneWhereTheBenchMovesAtTheStart) {
  const ErrorModel m = MemsClassModel();
  const BenchRun run = StillRun(m, 600.0, 7, 3, 20.0 * DriftSigma(m, 3), 120.0);
  const StartDeparture start = MeasureStartDeparture(run, m, kUpdateIntervalS, kStillToleranceRad, 1.5);
  for (int axis = 0; axis < kSensorAxisCount; ++axis) {
    EXPECT_EQ(start.start_square[static_cast<size_t>(axis)], 0.0) << "axis " << axis;
  }
}

// A table that turns from its first sample has no still start to measure.
TEST(StartDeparture, NoneWhereTheTableTurnsFromTheStart) {
  const ErrorModel m = MemsClassModel();
  BenchRun run = StillRun(m, 600.0, 8, 0, 20.0 * DriftSigma(m, 0), 120.0);
  for (ImuSample& s : run.samples) s.ref_rpy_rad.z() = 0.1 * s.t_s;
  const StartDeparture start = MeasureStartDeparture(run, m, kUpdateIntervalS, kStillToleranceRad, std::nullopt);
  for (int axis = 0; axis < kSensorAxisCount; ++axis) {
    EXPECT_EQ(start.window_s[static_cast<size_t>(axis)], 0.0) << "axis " << axis;
  }
}

}  // namespace
}  // namespace insdiag::engine
