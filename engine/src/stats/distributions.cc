#include "insdiag/engine/stats/distributions.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

namespace insdiag::engine::stats {
namespace {

constexpr int kMaxIterations = 1000;
constexpr double kEpsilon = 1e-15;

double GammaSeries(double a, double x) {
  // γ(a,x)/Γ(a) = e^{−x} x^a / Γ(a+1) · Σ x^n / ((a+1)…(a+n))   (A&S 6.5.29)
  double term = 1.0 / a;
  double sum = term;
  for (int n = 1; n < kMaxIterations; ++n) {
    term *= x / (a + n);
    sum += term;
    if (std::abs(term) < std::abs(sum) * kEpsilon) break;
  }
  return sum * std::exp(-x + a * std::log(x) - std::lgamma(a));
}

double GammaContinuedFraction(double a, double x) {
  // Γ(a,x)/Γ(a) by its continued fraction (A&S 6.5.31), modified Lentz.
  constexpr double kTiny = 1e-300;
  double b = x + 1.0 - a;
  double c = 1.0 / kTiny;
  double d = 1.0 / b;
  double h = d;
  for (int i = 1; i < kMaxIterations; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < kEpsilon) break;
  }
  return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
}

}  // namespace

double RegularizedGammaP(double a, double x) {
  if (x <= 0.0) return 0.0;
  if (x < a + 1.0) return GammaSeries(a, x);
  return 1.0 - GammaContinuedFraction(a, x);
}

double RegularizedGammaQ(double a, double x) {
  if (x <= 0.0) return 1.0;
  if (x < a + 1.0) return 1.0 - GammaSeries(a, x);
  return GammaContinuedFraction(a, x);
}

double ChiSquareCdf(double x, double dof) { return RegularizedGammaP(0.5 * dof, 0.5 * x); }
double ChiSquareSurvival(double x, double dof) { return RegularizedGammaQ(0.5 * dof, 0.5 * x); }

double ChiSquareQuantile(double p, double dof) {
  if (p <= 0.0) return 0.0;
  if (p >= 1.0) return std::numeric_limits<double>::infinity();
  // Bracket, then bisect on the survival function (robust in both tails).
  double lo = 0.0;
  double hi = std::max(1.0, dof);
  while (ChiSquareCdf(hi, dof) < p) hi *= 2.0;
  for (int i = 0; i < 200 && hi - lo > 1e-12 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (ChiSquareSurvival(mid, dof) > 1.0 - p) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return 0.5 * (lo + hi);
}

double NormalCdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

double NormalQuantile(double p) {
  if (p <= 0.0) return -std::numeric_limits<double>::infinity();
  if (p >= 1.0) return std::numeric_limits<double>::infinity();
  double lo = -40.0;
  double hi = 40.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (NormalCdf(mid) < p) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return 0.5 * (lo + hi);
}

double LjungBoxPValue(std::span<const double> series, int lags) {
  const auto n = static_cast<int>(series.size());
  if (lags < 1 || n <= lags + 1) return 1.0;
  const double mean = std::accumulate(series.begin(), series.end(), 0.0) / n;
  double c0 = 0.0;
  for (double v : series) c0 += (v - mean) * (v - mean);
  if (c0 <= 0.0) return 1.0;
  double q = 0.0;
  for (int h = 1; h <= lags; ++h) {
    double ch = 0.0;
    for (int t = h; t < n; ++t) ch += (series[static_cast<size_t>(t)] - mean) * (series[static_cast<size_t>(t - h)] - mean);
    const double rho = ch / c0;
    q += rho * rho / (n - h);
  }
  q *= static_cast<double>(n) * (n + 2);
  return ChiSquareSurvival(q, lags);
}

namespace {

// ψ(x).
double Digamma(double x) {
  double r = 0.0;
  while (x < 6.0) {
    r -= 1.0 / x;
    x += 1.0;
  }
  const double f = 1.0 / (x * x);
  return r + std::log(x) - 0.5 / x -
         f * (1.0 / 12 - f * (1.0 / 120 - f * (1.0 / 252 - f * (1.0 / 240 - f / 132))));
}

// ψ′(x).
double Trigamma(double x) {
  double r = 0.0;
  while (x < 6.0) {
    r += 1.0 / (x * x);
    x += 1.0;
  }
  const double f = 1.0 / (x * x);
  return r + 1.0 / x + 0.5 * f + f / x * (1.0 / 6 - f * (1.0 / 30 - f * (1.0 / 42 - f / 30)));
}

}  // namespace

double LogChiSquareMeanOffset(double dof) { return Digamma(0.5 * dof) - std::log(0.5 * dof); }

double LogChiSquareVariance(double dof) { return Trigamma(0.5 * dof); }

void HolmAdjust(std::span<const double> p, std::span<double> adjusted) {
  const size_t m = p.size();
  std::vector<size_t> order(m);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return p[a] < p[b]; });
  double running = 0.0;
  for (size_t rank = 0; rank < m; ++rank) {
    const double value = std::min(1.0, static_cast<double>(m - rank) * p[order[rank]]);
    running = std::max(running, value);
    adjusted[order[rank]] = running;
  }
}

}  // namespace insdiag::engine::stats
