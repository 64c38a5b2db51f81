#include "support/monte_carlo.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string_view>

namespace insdiag::testing {
namespace {

// P(X = j) for X ~ Binomial(n, p), through the log-gamma function so that
// it keeps its digits for hundreds of runs.
double Pmf(int n, double p, int j) {
  if (p <= 0.0) return j == 0 ? 1.0 : 0.0;
  if (p >= 1.0) return j == n ? 1.0 : 0.0;
  const double log_choose = std::lgamma(n + 1.0) - std::lgamma(j + 1.0) - std::lgamma(n - j + 1.0);
  return std::exp(log_choose + j * std::log(p) + (n - j) * std::log1p(-p));
}

}  // namespace

bool FullSweep() {
  const char* sweep = std::getenv("INSDIAG_SWEEP");
  return sweep != nullptr && std::string_view(sweep) == "full";
}

int Runs(MonteCarloSize size) { return FullSweep() ? size.sweep : size.suite; }

double ChanceOfFewer(int runs, double rate, int k) {
  double sum = 0.0;
  for (int j = 0; j < std::min(k, runs + 1); ++j) sum += Pmf(runs, rate, j);
  return std::min(sum, 1.0);
}

double ChanceOfMore(int runs, double rate, int k) {
  double sum = 0.0;
  for (int j = std::max(k + 1, 0); j <= runs; ++j) sum += Pmf(runs, rate, j);
  return std::min(sum, 1.0);
}

int LeastSuccesses(int runs, double claimed_rate, double false_failure) {
  int k = 0;
  while (k < runs && ChanceOfFewer(runs, claimed_rate, k + 1) <= false_failure) ++k;
  return k;
}

int MostAlarms(int runs, double alarm_rate, double false_failure) {
  int m = 0;
  while (m < runs && ChanceOfMore(runs, alarm_rate, m) > false_failure) ++m;
  return m;
}

}  // namespace insdiag::testing
