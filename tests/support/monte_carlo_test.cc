// The Monte Carlo thresholds against binomial probabilities worked by hand.
#include "support/monte_carlo.h"

#include <gtest/gtest.h>
#include <stdlib.h>

namespace insdiag::testing {
namespace {

TEST(MonteCarlo, BinomialTailsAreTheHandWorkedOnes) {
  // Four fair coins: P(X < 2) = (1 + 4)/16, P(X > 2) = (4 + 1)/16.
  EXPECT_NEAR(ChanceOfFewer(4, 0.5, 2), 5.0 / 16.0, 1e-15);
  EXPECT_NEAR(ChanceOfMore(4, 0.5, 2), 5.0 / 16.0, 1e-15);
  EXPECT_DOUBLE_EQ(ChanceOfFewer(4, 0.5, 0), 0.0);
  EXPECT_DOUBLE_EQ(ChanceOfMore(4, 0.5, 4), 0.0);
  // Three runs at 0.9: P(X = 0) = 0.001, P(X = 1) = 3 · 0.9 · 0.01 = 0.027.
  EXPECT_NEAR(ChanceOfFewer(3, 0.9, 2), 0.028, 1e-12);
  // Twenty runs at 0.01: P(X > 1) = 1 − 0.99²⁰ − 20 · 0.01 · 0.99¹⁹ = 0.016859.
  EXPECT_NEAR(ChanceOfMore(20, 0.01, 1), 0.0168593, 1e-6);
  // Hundreds of runs keep their digits: P(X < 200) at 0.5 of 400 = (1 − P(X = 200))/2.
  EXPECT_NEAR(ChanceOfFewer(400, 0.5, 200), 0.4801, 1e-4);
}

TEST(MonteCarlo, LeastSuccessesIsTheClaimsThresholdAtTheFalseFailureProbability) {
  // Three runs at 0.9: fewer than 1 has 0.001 ≤ 0.01, fewer than 2 has 0.028.
  EXPECT_EQ(LeastSuccesses(3, 0.9, 0.01), 1);
  EXPECT_EQ(LeastSuccesses(3, 0.9, 0.03), 2);
  // Ten runs at 0.95: P(X < 8) = 0.0115, P(X < 7) = 0.00103.
  EXPECT_EQ(LeastSuccesses(10, 0.95, 0.01), 7);
  EXPECT_EQ(LeastSuccesses(10, 0.95, 0.02), 8);
  // Every run must succeed where one miss is already unlikely: 1 − 0.999⁵ = 0.005.
  EXPECT_EQ(LeastSuccesses(5, 0.999, 0.01), 5);
  // One run cannot test a rate of 0.9 at 1 %: the threshold is 0.
  EXPECT_EQ(LeastSuccesses(1, 0.9, 0.01), 0);
}

TEST(MonteCarlo, MostAlarmsIsTheFalseAlarmRatesThresholdAtTheFalseFailureProbability) {
  // Twenty runs at α = 1 %: P(X > 1) = 0.0169, P(X > 2) = 0.00101.
  EXPECT_EQ(MostAlarms(20, 0.01, 0.02), 1);
  EXPECT_EQ(MostAlarms(20, 0.01, 0.01), 2);
  // Two runs: P(X > 0) = 1 − 0.99² = 0.0199.
  EXPECT_EQ(MostAlarms(2, 0.01, 0.02), 0);
  EXPECT_EQ(MostAlarms(2, 0.01, 0.01), 1);
  // One run at α = 10 % cannot be tested at 1 %: every run may alarm.
  EXPECT_EQ(MostAlarms(1, 0.1, 0.01), 1);
}

TEST(MonteCarlo, TheSweepsSizeOnlyWhenAskedFor) {
  const MonteCarloSize size{3, 20};
  unsetenv("INSDIAG_SWEEP");
  EXPECT_FALSE(FullSweep());
  EXPECT_EQ(Runs(size), 3);
  setenv("INSDIAG_SWEEP", "yes", 1);
  EXPECT_EQ(Runs(size), 3);
  setenv("INSDIAG_SWEEP", "full", 1);
  EXPECT_TRUE(FullSweep());
  EXPECT_EQ(Runs(size), 20);
  unsetenv("INSDIAG_SWEEP");
}

}  // namespace
}  // namespace insdiag::testing
