// The Allan variance of a first-order Gauss–Markov process, R(t) = σ² e^{−|t|/T}:
//   σ²(τ) = σ² g(τ/T),  g(u) = (2u − 3 + 4e^{−u} − e^{−2u})/u²
// (IEEE Std 952-1997, Annex C, exponentially correlated noise). Shared by the
// Allan fit (ident/allan.h) and the flicker floor the model carries as a sum
// of such processes (model/flicker_floor.h).
#pragma once

#include <array>
#include <cmath>

#include "insdiag/engine/numerics/golden_section.h"

namespace insdiag::engine {

// g(u) = (2u − 3 + 4e^{−u} − e^{−2u})/u², the Markov term's AVAR shape
// (u = τ/T). Below u = 0.1 the closed form cancels to O(u³); there we use its
// Taylor series g(u) = Σ_{k≥3} (−1)^k (4 − 2^k)/k! · u^{k−2} (to k = 11).
constexpr std::array<double, 9> MarkovSeriesCoefficients() {
  std::array<double, 9> c{};
  double factorial = 2.0;
  for (int k = 3; k < 12; ++k) {
    factorial *= k;
    double two_k = 1.0;
    for (int i = 0; i < k; ++i) two_k *= 2.0;
    c[static_cast<size_t>(k - 3)] = (k % 2 == 1 ? -1.0 : 1.0) * (4.0 - two_k) / factorial;
  }
  return c;
}
inline constexpr std::array<double, 9> kMarkovSeries = MarkovSeriesCoefficients();

// Also at a complex u: a second-order pair's Allan variance is σ₂² Re g(λT)
// with λ = α − iβ (drift_ceiling.h).
template <typename T>
T MarkovShape(const T& u) {
  using std::abs;
  using std::exp;
  if (abs(u) < 0.1) {
    T sum(kMarkovSeries.back());
    for (int i = static_cast<int>(kMarkovSeries.size()) - 2; i >= 0; --i) {
      sum = sum * u + T(kMarkovSeries[static_cast<size_t>(i)]);
    }
    return sum * u;
  }
  return (T(2.0) * u - T(3.0) + T(4.0) * exp(-u) - exp(T(-2.0) * u)) / (u * u);
}

// Peak of g: u* and g(u*) (golden-section search; g is unimodal on (0, ∞)).
struct MarkovPeak {
  double u = 0.0;
  double g = 0.0;
};
inline const MarkovPeak& MarkovShapePeak() {
  static const MarkovPeak peak = [] {
    constexpr double kLo = 0.5, kHi = 6.0, kTolerance = 1e-12;  // g peaks near u = 1.89
    const auto [g, u] = numerics::GoldenSectionMaximum(kLo, kHi, kLo, MarkovShape(kLo), kTolerance,
                                                       MarkovShape<double>);
    return MarkovPeak{u, g};
  }();
  return peak;
}

}  // namespace insdiag::engine
