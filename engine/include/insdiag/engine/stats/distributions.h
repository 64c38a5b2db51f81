// Distribution functions for the engine's tests of fit.
//
//   P(a, x) = γ(a, x)/Γ(a), Q = 1 − P       regularised incomplete gamma
//     series for x < a + 1, continued fraction (modified Lentz) otherwise
//     (Abramowitz & Stegun, Handbook of Mathematical Functions, 6.5.29 and 6.5.31)
//   χ²_k:  F(x) = P(k/2, x/2)
//   N(0,1): Φ(x) = ½ erfc(−x/√2)
//   ln of a χ²_ν/ν variate: mean ψ(ν/2) − ln(ν/2), variance ψ′(ν/2) (ψ digamma,
//     ψ′ trigamma; e.g. Bartlett & Kendall, JRSS Suppl. 8(1), 1946); ψ by
//     recurrence to x ≥ 6 and A&S 6.3.18, ψ′ likewise and A&S 6.4.12
//   Ljung–Box: Q = N(N+2) Σ_{h=1}^{H} ρ̂_h²/(N−h) ~ χ²_H under whiteness
//     (Ljung & Box, Biometrika 65(2), 1978)
#pragma once

#include <span>

namespace insdiag::engine::stats {

double RegularizedGammaP(double a, double x);
double RegularizedGammaQ(double a, double x);

double ChiSquareCdf(double x, double dof);
double ChiSquareSurvival(double x, double dof);  // 1 − F, accurate in the far tail
double ChiSquareQuantile(double p, double dof);  // x with F(x) = p

// E ln(χ²_ν/ν) and Var ln(χ²_ν/ν): a variance estimate with ν degrees of
// freedom, on a log scale.
double LogChiSquareMeanOffset(double dof);
double LogChiSquareVariance(double dof);

double NormalCdf(double x);
double NormalQuantile(double p);

// p-value of the Ljung–Box portmanteau test on `series` (mean removed) with
// `lags` lags; 1 when the series is too short.
double LjungBoxPValue(std::span<const double> series, int lags);

// Holm's step-down adjustment of p-values (Holm, Scand. J. Statistics 6, 1979):
// adjusted p_(i) = max_{j ≤ i} min(1, (m − j + 1) p_(j)) in ascending order.
void HolmAdjust(std::span<const double> p, std::span<double> adjusted);

}  // namespace insdiag::engine::stats
