// Monte Carlo claims at two sizes. A statistical test states a claim — a
// detection rate, an interval's coverage, a false-alarm rate — checks it
// over some number of seeded runs, and fails when the count of successes
// (or alarms) is one the claimed rate makes unlikely. The suite runs each
// such test at the smallest size that still tests its claim; the full
// sweep (INSDIAG_SWEEP=full, scripts/sweeps.sh) runs the same test body at
// the size whose figures the docs quote. The thresholds come from the
// exact binomial distribution at a stated false-failure probability, so a
// test's threshold follows its size instead of being written by hand.
#pragma once

namespace insdiag::testing {

// The number of runs (seeds, scenarios) of a Monte Carlo test: `suite` in
// the test suite, `sweep` in the full sweep.
struct MonteCarloSize {
  int suite;
  int sweep;
};

// True when INSDIAG_SWEEP=full: the sweep's sizes instead of the suite's.
bool FullSweep();

// `size.sweep` in the full sweep, else `size.suite`.
int Runs(MonteCarloSize size);

// P(X < k) and P(X > k) for X ~ Binomial(runs, rate).
double ChanceOfFewer(int runs, double rate, int k);
double ChanceOfMore(int runs, double rate, int k);

// The threshold for a claimed success rate: the largest k such that, were
// every run a success with probability `claimed_rate` independently, fewer
// than k successes in `runs` runs would happen with probability at most
// `false_failure`. A test asserts successes ≥ k. It is 0 when `runs` is too
// small to test the claim at that probability (a test must not use it so).
int LeastSuccesses(int runs, double claimed_rate, double false_failure);

// The mirror for a claimed false-alarm rate: the fewest alarms m such that,
// were every run to alarm with probability `alarm_rate` independently, more
// than m alarms in `runs` runs would happen with probability at most
// `false_failure`. A test asserts alarms ≤ m. It equals `runs` when `runs`
// is too small to test the claim at that probability.
int MostAlarms(int runs, double alarm_rate, double false_failure);

}  // namespace insdiag::testing
