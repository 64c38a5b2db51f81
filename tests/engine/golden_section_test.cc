// numerics::GoldenSectionMaximum (numerics/golden_section.h): the maximum of a
// unimodal function to the bracket's tolerance, an end of the range where the
// function still rises there, and the start where nothing beats it.
#include "insdiag/engine/numerics/golden_section.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace insdiag::engine::numerics {
namespace {

constexpr double kTolerance = 1e-4;

// A Gaussian log-likelihood in a variance's logarithm, ℓ(u) = −½(n u + S e^{−u}),
// peaks at u = ln(S/n): the shape the reference-noise fit searches.
TEST(GoldenSectionMaximum, FindsTheMaximumOfALogLikelihoodInALogVarianceWithinItsTolerance) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> peak(-8.0, 2.0);
  for (int trial = 0; trial < 20; ++trial) {
    const double n = 1000.0, u_star = peak(rng), sum = n * std::exp(u_star);
    int evaluations = 0;
    const auto l = [&](double u) {
      ++evaluations;
      return -0.5 * (n * u + sum * std::exp(-u));
    };
    const auto [top, u] = GoldenSectionMaximum(-10.0, 4.0, -10.0, l(-10.0), kTolerance, l);
    EXPECT_NEAR(u, u_star, kTolerance) << "trial " << trial;
    EXPECT_DOUBLE_EQ(top, l(u));
    // Each step keeps 1/φ of the bracket: ln(14/1e-4)/ln φ ≈ 25 steps.
    EXPECT_LE(evaluations, 32);
  }
}

TEST(GoldenSectionMaximum, GivesTheRangesEndWhereTheFunctionStillRisesThere) {
  const auto rising = [](double x) { return x; };
  EXPECT_DOUBLE_EQ(GoldenSectionMaximum(0.0, 3.0, 0.0, 0.0, kTolerance, rising).second, 3.0);
  const auto falling = [](double x) { return -x; };
  EXPECT_DOUBLE_EQ(GoldenSectionMaximum(0.0, 3.0, 1.5, -1.5, kTolerance, falling).second, 0.0);
}

TEST(GoldenSectionMaximum, KeepsTheStartWhereNothingBeatsIt) {
  // The start's value is given, not evaluated: a point the search never reaches.
  const auto flat = [](double) { return 0.0; };
  const auto [top, x] = GoldenSectionMaximum(0.0, 1.0, 5.0, 1.0, kTolerance, flat);
  EXPECT_DOUBLE_EQ(x, 5.0);
  EXPECT_DOUBLE_EQ(top, 1.0);
}

}  // namespace
}  // namespace insdiag::engine::numerics
