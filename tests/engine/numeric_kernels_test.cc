// The numeric kernels checked directly, against what is known without them:
// the matrix exponential against closed forms, the distribution functions
// against published table values, and the one-pass score test against the
// filter with the effect augmented (the quantity the score test claims to
// compute without running it).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include <Eigen/Core>

#include "insdiag/engine/filter/epoch_run.h"
#include "insdiag/engine/filter/forward_filter.h"
#include "insdiag/engine/finder/score_test.h"
#include "insdiag/engine/model/state_layout.h"
#include "insdiag/engine/numerics/matrix_exponential.h"
#include "insdiag/engine/sim/simulator.h"
#include "insdiag/engine/stats/distributions.h"
#include "scenarios.h"

namespace insdiag::engine {
namespace {

// --- matrix exponential -----------------------------------------------------

// A rotation generator's exponential is the rotation; its integral is
// ∫₀ᵗ R(ωs) ds = [sin ωt, cos ωt − 1; 1 − cos ωt, sin ωt] / ω.
TEST(MatrixExponential, OfARotationGeneratorIsTheRotationAndItsIntegral) {
  const double w = 0.7, t = 2.3;
  Eigen::MatrixXd F(2, 2);
  F << 0.0, -w, w, 0.0;
  const auto e = numerics::ExponentialWithIntegral(F, t);
  Eigen::MatrixXd rotation(2, 2), integral(2, 2);
  rotation << std::cos(w * t), -std::sin(w * t), std::sin(w * t), std::cos(w * t);
  integral << std::sin(w * t), std::cos(w * t) - 1.0, 1.0 - std::cos(w * t), std::sin(w * t);
  integral /= w;
  EXPECT_LT((e.exponential - rotation).cwiseAbs().maxCoeff(), 1e-13);
  EXPECT_LT((e.integral - integral).cwiseAbs().maxCoeff(), 1e-13);
}

// A first-order Gauss–Markov block −1/τ: e^{−t/τ} and τ (1 − e^{−t/τ}); a
// nilpotent (position–velocity) block: [1 t; 0 1] and [t t²/2; 0 t].
TEST(MatrixExponential, OfADecayAndOfANilpotentBlockAreTheirClosedForms) {
  const double tau = 1800.0, t = 37.0;
  Eigen::MatrixXd decay(1, 1);
  decay << -1.0 / tau;
  const auto d = numerics::ExponentialWithIntegral(decay, t);
  EXPECT_NEAR(d.exponential(0, 0), std::exp(-t / tau), 1e-14);  // a few units in the last place
  EXPECT_NEAR(d.integral(0, 0), tau * -std::expm1(-t / tau), 1e-12);

  Eigen::MatrixXd nilpotent(2, 2);
  nilpotent << 0.0, 1.0, 0.0, 0.0;
  const auto n = numerics::ExponentialWithIntegral(nilpotent, t);
  Eigen::MatrixXd exponential(2, 2), integral(2, 2);
  exponential << 1.0, t, 0.0, 1.0;
  integral << t, 0.5 * t * t, 0.0, t;
  EXPECT_LT((n.exponential - exponential).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((n.integral - integral).cwiseAbs().maxCoeff(), 1e-10);
}

// A large-norm diagonal matrix takes the scaling and squaring: e^{diag(d)} = diag(e^d).
TEST(MatrixExponential, OfADiagonalIsTheExponentialOfEachElement) {
  Eigen::MatrixXd D = Eigen::MatrixXd::Zero(3, 3);
  D.diagonal() << -20.0, 0.5, 7.0;
  const Eigen::MatrixXd e = numerics::MatrixExponential(D);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(e(i, i) / std::exp(D(i, i)), 1.0, 1e-12) << i;
  EXPECT_EQ((e - Eigen::MatrixXd(e.diagonal().asDiagonal())).cwiseAbs().maxCoeff(), 0.0);
}

// --- distributions ----------------------------------------------------------

// χ² quantiles as tabulated (Abramowitz & Stegun, Table 26.8; NIST/SEMATECH
// e-Handbook of Statistical Methods, §1.3.6.7.4), to the table's 3 decimals.
TEST(Distributions, ChiSquareQuantilesMatchThePublishedTable) {
  struct Row {
    double p, dof, x;
  };
  for (const Row& r : std::vector<Row>{{0.95, 1, 3.841},   {0.95, 2, 5.991},  {0.95, 10, 18.307},
                                       {0.99, 5, 15.086},  {0.05, 10, 3.940}, {0.999, 3, 16.266},
                                       {0.01, 30, 14.953}, {0.5, 1, 0.455}}) {
    EXPECT_NEAR(stats::ChiSquareQuantile(r.p, r.dof), r.x, 6e-4) << "p " << r.p << ", dof " << r.dof;
    EXPECT_NEAR(stats::ChiSquareCdf(r.x, r.dof), r.p, 1e-4) << "x " << r.x << ", dof " << r.dof;
  }
  // The far tail, where 1 − F would cancel: χ²_1 at 100 is erfc(√50) = 2.088e-23.
  EXPECT_NEAR(stats::ChiSquareSurvival(100.0, 1.0) / std::erfc(std::sqrt(50.0)), 1.0, 1e-9);
}

// Standard normal values (A&S Tables 26.1 and 26.5).
TEST(Distributions, NormalCdfAndQuantileMatchThePublishedTable) {
  EXPECT_NEAR(stats::NormalCdf(1.0), 0.8413447461, 1e-9);
  EXPECT_NEAR(stats::NormalCdf(-2.0), 0.0227501319, 1e-9);
  EXPECT_NEAR(stats::NormalQuantile(0.975), 1.959963985, 1e-8);
  EXPECT_NEAR(stats::NormalQuantile(0.995), 2.575829304, 1e-8);
  EXPECT_NEAR(stats::NormalQuantile(1e-6), -4.753424309, 1e-7);
}

// The incomplete gamma's closed forms: P(1, x) = 1 − e^{−x}, P(½, x) = erf √x.
TEST(Distributions, IncompleteGammaMatchesItsClosedForms) {
  for (double x : {0.01, 0.5, 1.0, 3.0, 10.0, 40.0}) {
    EXPECT_NEAR(stats::RegularizedGammaP(1.0, x), -std::expm1(-x), 1e-13) << x;
    EXPECT_NEAR(stats::RegularizedGammaP(0.5, x), std::erf(std::sqrt(x)), 1e-13) << x;
    EXPECT_NEAR(stats::RegularizedGammaP(2.5, x) + stats::RegularizedGammaQ(2.5, x), 1.0, 1e-14) << x;
  }
}

// ln(χ²_ν/ν) at ν = 2: mean ψ(1) − ln 1 = −γ (Euler's constant), variance ψ′(1) = π²/6.
// The asymptotic series after the recurrence to x ≥ 6 (A&S 6.3.18, 6.4.12) is
// truncated: good to about 1e-11 for ψ and 2e-10 for ψ′, far below the spread
// of any variance estimate these moments describe.
TEST(Distributions, LogChiSquareMomentsMatchTheDigammaValues) {
  constexpr double kSeriesTolerance = 1e-9;
  EXPECT_NEAR(stats::LogChiSquareMeanOffset(2.0), -0.5772156649015329, kSeriesTolerance);
  EXPECT_NEAR(stats::LogChiSquareVariance(2.0), std::numbers::pi * std::numbers::pi / 6.0, kSeriesTolerance);
  // ν = 1: ψ(½) − ln ½ = (−γ − 2 ln 2) + ln 2, ψ′(½) = π²/2.
  EXPECT_NEAR(stats::LogChiSquareMeanOffset(1.0), -0.5772156649015329 - std::log(2.0), kSeriesTolerance);
  EXPECT_NEAR(stats::LogChiSquareVariance(1.0), std::numbers::pi * std::numbers::pi / 2.0, kSeriesTolerance);
}

// Holm's step-down by hand: sorted 0.01, 0.03, 0.04 of three → 0.03, 0.06, 0.06.
TEST(Distributions, HolmAdjustsAsItsStepDownDoesByHand) {
  const std::vector<double> p = {0.01, 0.04, 0.03};
  std::vector<double> adjusted(3);
  stats::HolmAdjust(p, adjusted);
  EXPECT_NEAR(adjusted[0], 0.03, 1e-15);
  EXPECT_NEAR(adjusted[1], 0.06, 1e-15);
  EXPECT_NEAR(adjusted[2], 0.06, 1e-15);
}

// Ljung–Box by its definition on a short series, written out here.
TEST(Distributions, LjungBoxIsItsStatisticsChiSquareTail) {
  const std::vector<double> series = {0.3, -1.2, 0.8, 2.1, -0.4, -0.9, 1.5, 0.2, -1.7, 0.6, 1.1, -0.3};
  const int lags = 3;
  const auto n = static_cast<double>(series.size());
  double mean = 0.0;
  for (double v : series) mean += v / n;
  double c0 = 0.0;
  for (double v : series) c0 += (v - mean) * (v - mean);
  double q = 0.0;
  for (int h = 1; h <= lags; ++h) {
    double ch = 0.0;
    for (size_t i = static_cast<size_t>(h); i < series.size(); ++i) {
      ch += (series[i] - mean) * (series[i - static_cast<size_t>(h)] - mean);
    }
    q += (ch / c0) * (ch / c0) / (n - h);
  }
  q *= n * (n + 2.0);
  EXPECT_NEAR(stats::LjungBoxPValue(series, lags), stats::ChiSquareSurvival(q, lags), 1e-12);
}

// --- the score test against the augmented filter -----------------------------

// With the condensed run fixed, the filter is linear in the sensor states, and
// the innovations' log-likelihood with a constant effect β ~ N(0, σ²) added as
// a state is exactly (the score test's quadratic, score_test.h, integrated
// over the prior)
//   ℓ_aug − ℓ₀ = ½ s² / (𝓘 + σ⁻²) − ½ ln(1 + σ² 𝓘)
// and its final estimate of β is the posterior mean s / (𝓘 + σ⁻²).
TEST(ScoreTest, EqualsTheFilterWithTheEffectAugmented) {
  sim::SimulatedUnit unit = testing::NavigationGradeUnit();
  auto hidden = sim::ParseTrueEffect("gyro_scale_factor.z=8e-5");
  ASSERT_TRUE(hidden.ok()) << hidden.status();
  unit.effects = *hidden;
  const sim::SimulatedRun sim = testing::SimulateOrDie(unit, testing::ShortTurnsProfile(300.0, 1200.0), 10.0, 5);
  const ErrorModel model = testing::TrueBaseModel(unit);
  auto epochs = CondenseRun(sim.run, model, 1.0);
  ASSERT_TRUE(epochs.ok()) << epochs.status();

  const StateLayout layout(model);
  ScoreTestObserver scan(layout, *epochs, AbsentConstantCandidates(model), 60);
  auto plain = RunForwardFilter(*epochs, model, &scan);
  ASSERT_TRUE(plain.ok()) << plain.status();
  int column = -1;
  for (size_t c = 0; c < scan.columns().size(); ++c) {
    if (scan.columns()[c].term.Name() == "gyro_scale_factor.z") column = static_cast<int>(c);
  }
  ASSERT_GE(column, 0);
  const double s = scan.score()[column];
  const double information = scan.information()(column, column);
  ASSERT_GT(information, 0.0);

  for (const double prior_sigma : {2e-5, 1e-4, 1e-3}) {
    ErrorModel augmented = model;
    ModelEffect effect;
    effect.term = scan.columns()[static_cast<size_t>(column)].term;
    effect.prior_sigma = {prior_sigma, 0.0};
    augmented.effects.push_back(effect);
    auto with = RunForwardFilter(*epochs, augmented);
    ASSERT_TRUE(with.ok()) << with.status();
    const double precision = information + 1.0 / (prior_sigma * prior_sigma);
    const double predicted_gain = 0.5 * s * s / precision - 0.5 * std::log1p(prior_sigma * prior_sigma * information);
    const double gain = with->log_likelihood - plain->log_likelihood;
    EXPECT_NEAR(gain, predicted_gain, 1e-6 * std::max(1.0, std::abs(predicted_gain))) << "prior σ " << prior_sigma;

    const StateLayout augmented_layout(augmented);
    int state = -1;
    for (const SensorState& st : augmented_layout.sensor_states()) {
      if (st.effect == 0) state = st.index;
    }
    ASSERT_GE(state, 0);
    const double estimate = with->x_filt(with->epochs() - 1, state);
    EXPECT_NEAR(estimate, s / precision, 1e-6 * std::abs(s / precision)) << "prior σ " << prior_sigma;
  }
  // And the one-step estimate finds the hidden effect, within its standard error's few multiples.
  EXPECT_NEAR(s / information, 8e-5, 4.0 / std::sqrt(information));
}

}  // namespace
}  // namespace insdiag::engine
