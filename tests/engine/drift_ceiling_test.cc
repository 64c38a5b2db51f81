// The drifts a channel's raw samples allow (ident/drift_ceiling.h), on
// simulated one-hour still segments: the unit's own drift is allowed at the
// ceiling's family-wise level, and a drift that wanders far beyond the
// samples is refused.
#include "insdiag/engine/ident/drift_ceiling.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

namespace insdiag::engine::ident {
namespace {

constexpr double kSampleIntervalS = 0.1;  // 10 Hz
constexpr int kSamples = 36000;           // one hour
constexpr double kFamilyWiseAlpha = 0.01;
constexpr DriftAxis kGyroX{Sensor::kGyro, 0};

// A still channel: white rate noise of σ `white_rate` per sample on a
// first-order Gauss–Markov drift (exact discretisation, seed eq. 5).
std::vector<double> StillChannel(const GaussMarkov& drift, double white_rate,
                                 std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  const double phi = std::exp(-kSampleIntervalS / drift.tau_s);
  const double innovation = drift.sigma * std::sqrt(1.0 - phi * phi);
  std::vector<double> y(kSamples);
  double b = drift.sigma * n(rng);
  for (double& v : y) {
    v = b + white_rate * n(rng);
    b = phi * b + innovation * n(rng);
  }
  return y;
}

// The ceilings of one gyro channel holding `rates`.
DriftCeilings CeilingsOf(const std::vector<double>& rates) {
  const AllanOptions options;
  const std::vector<std::vector<double>> pieces = {rates};
  AllanResult allan;
  allan.tau0_s = kSampleIntervalS;
  AllanChannel channel;
  channel.name = "gyro_x";
  channel.curve = OverlappingAllanCurve(pieces, kSampleIntervalS,
                                        AllanClusterSizes(rates.size(), options), options);
  allan.channels.push_back(channel);
  return DriftCeilings::FromAllan(allan, kFamilyWiseAlpha);
}

// Drifts drawn over the classes a bench sees: τ from 30 s to 3 h, the white
// noise of one sample from 0.3 to 30 drift σ.
struct Draw {
  GaussMarkov drift;
  double white_rate = 0.0;
};
Draw DrawUnit(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double sigma = 1e-6;
  return {{sigma, 30.0 * std::pow(360.0, u(rng))}, sigma * 0.3 * std::pow(100.0, u(rng))};
}

// The unit's own drift is refused in at most α of the runs; the bound is
// Bonferroni over the curve's correlated points, so fewer are expected. Of
// 300 runs, α gives 3 on average; eight or more (P < 0.012 at α) fail.
TEST(DriftCeilingTest, TheUnitsOwnDriftIsAllowedAtTheFamilyWiseLevel) {
  constexpr int kRuns = 300;
  std::mt19937_64 rng(4601);
  int refused = 0;
  for (int run = 0; run < kRuns; ++run) {
    const Draw d = DrawUnit(rng);
    const DriftCeilings ceilings = CeilingsOf(StillChannel(d.drift, d.white_rate, rng));
    const DriftCeilings::Excess excess = ceilings.ExcessOf(kGyroX, d.drift);
    if (excess.ratio > 1.0) {
      ++refused;
      std::printf("run %d: τ %.0f s, white %.2f σ: refused, %.2f at %.0f s\n", run, d.drift.tau_s,
                  d.white_rate / d.drift.sigma, excess.ratio, excess.cluster_time_s);
    }
  }
  std::printf("the unit's own drift refused in %d of %d runs\n", refused, kRuns);
  EXPECT_LE(refused, 7);
}

// A drift that wanders as an unobservable one was fitted to (σ 30 times the
// unit's, τ ten times the run) is refused in nearly every run, as is σ ten
// times the unit's at its own τ. Within the ceiling, the largest σ
// allowed at a τ is allowed, and a little more is not.
TEST(DriftCeilingTest, ADriftFarBeyondTheSamplesIsRefused) {
  constexpr int kRuns = 100;
  std::mt19937_64 rng(4602);
  int wandering_refused = 0;
  int tenfold_refused = 0;
  for (int run = 0; run < kRuns; ++run) {
    const Draw d = DrawUnit(rng);
    const DriftCeilings ceilings = CeilingsOf(StillChannel(d.drift, d.white_rate, rng));
    const GaussMarkov wandering{30.0 * d.drift.sigma, 10.0 * kSamples * kSampleIntervalS};
    const GaussMarkov tenfold{10.0 * d.drift.sigma, d.drift.tau_s};
    wandering_refused += ceilings.Allows(kGyroX, wandering) ? 0 : 1;
    tenfold_refused += ceilings.Allows(kGyroX, tenfold) ? 0 : 1;
    const double largest = ceilings.LargestSigma(kGyroX, d.drift.tau_s);
    EXPECT_TRUE(ceilings.Allows(kGyroX, {0.999 * largest, d.drift.tau_s}));
    EXPECT_FALSE(ceilings.Allows(kGyroX, {1.001 * largest, d.drift.tau_s}));
    EXPECT_EQ(ceilings.Within(kGyroX, wandering).tau_s, wandering.tau_s);
    EXPECT_TRUE(ceilings.Allows(kGyroX, ceilings.Within(kGyroX, wandering)));
  }
  std::printf("refused: σ ×30 at τ ×10 the run %d of %d, σ ×10 at its τ %d of %d\n",
              wandering_refused, kRuns, tenfold_refused, kRuns);
  EXPECT_GE(wandering_refused, 95);
  EXPECT_GE(tenfold_refused, 95);
}

// The Allan variance the ceiling predicts at one cluster time (a ceiling of
// one point and bound 1 reads it as the ratio).
double PredictedAllanVariance(double cluster_time_s, const AllanNoiseTerms& terms,
                              const DriftCeilings::SecondOrderPair& pair) {
  DriftCeilings unit_bound;
  unit_bound.Add(kGyroX, {cluster_time_s, 1.0});
  return unit_bound.ExcessOf(kGyroX, terms, pair).ratio;
}

// A second-order pair's Allan variance, σ₂² Re g(λT) with λ = α − iβ: equal
// to the Gauss–Markov process's where β = 0, and the mean of the measured
// curve over simulated one-hour channels of a pair (decay 100 s, period
// 300 s) within 8 % of it at cluster times short and long against the
// period (the mean of 60 curves: its own error is about 3 % at 150 s).
TEST(DriftCeilingTest, ASecondOrderPairsAllanVarianceIsTheComplexRateMarkovs) {
  const DriftCeilings::SecondOrderPair still{1.0, 1.0 / 100.0, 0.0};
  AllanNoiseTerms markov;
  markov.markov_sigma = 1.0;
  markov.markov_tau_s = 100.0;
  for (double t : {0.5, 10.0, 100.0, 1000.0}) {
    EXPECT_NEAR(PredictedAllanVariance(t, {}, still), PredictedAllanVariance(t, markov, {}),
                1e-9 * PredictedAllanVariance(t, markov, {}))
        << t;
  }
  const DriftCeilings::SecondOrderPair pair{1.0, 1.0 / 100.0, 2.0 * 3.141592653589793 / 300.0};
  const double rho = std::exp(-pair.decay_rate_per_s * kSampleIntervalS);
  const double angle = pair.frequency_rad_s * kSampleIntervalS;
  const double innovation = pair.sigma * std::sqrt(1.0 - rho * rho);
  const std::vector<double> cluster_times_s = {10.0, 50.0, 150.0};
  std::vector<double> mean(cluster_times_s.size(), 0.0);
  constexpr int kRuns = 60;
  std::mt19937_64 rng(4603);
  std::normal_distribution<double> n(0.0, 1.0);
  const AllanOptions options;
  for (int run = 0; run < kRuns; ++run) {
    std::vector<double> y(kSamples);
    double a = pair.sigma * n(rng), b = pair.sigma * n(rng);
    for (double& v : y) {
      v = a;
      const double a_next = rho * (std::cos(angle) * a - std::sin(angle) * b) + innovation * n(rng);
      b = rho * (std::sin(angle) * a + std::cos(angle) * b) + innovation * n(rng);
      a = a_next;
    }
    const std::vector<std::vector<double>> pieces = {y};
    std::vector<int64_t> sizes;
    for (double t : cluster_times_s)
      sizes.push_back(static_cast<int64_t>(std::lround(t / kSampleIntervalS)));
    const std::vector<AllanPoint> curve =
        OverlappingAllanCurve(pieces, kSampleIntervalS, sizes, options);
    ASSERT_EQ(curve.size(), cluster_times_s.size());
    for (size_t j = 0; j < curve.size(); ++j) mean[j] += curve[j].adev * curve[j].adev / kRuns;
  }
  for (size_t j = 0; j < cluster_times_s.size(); ++j) {
    const double predicted = PredictedAllanVariance(cluster_times_s[j], {}, pair);
    std::printf("τ %.0f s: measured %.4g, predicted %.4g\n", cluster_times_s[j], mean[j],
                predicted);
    EXPECT_NEAR(mean[j], predicted, 0.08 * predicted) << cluster_times_s[j];
  }
}

// A run without static segments has no points: every drift is allowed.
TEST(DriftCeilingTest, WithoutStillSamplesEveryDriftIsAllowed) {
  const DriftCeilings none;
  EXPECT_TRUE(none.Allows(kGyroX, {1.0, 1e6}));
  EXPECT_TRUE(std::isinf(none.LargestSigma(kGyroX, 100.0)));
}

}  // namespace
}  // namespace insdiag::engine::ident
