// Golden-section search for the maximum of a unimodal function of one
// variable (Kiefer, Proc. AMS 4(3), 1953; Press et al., Numerical Recipes,
// 3rd ed., §10.2): each step keeps the golden share of the bracket, one new
// evaluation a step. Used for likelihoods in a variance's logarithm, where
// each evaluation is a whole filter pass.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

namespace insdiag::engine::numerics {

// The maximum of f over [lo_limit, hi_limit] to a bracket `tolerance` wide:
// the bracket's best point, or an end of the range when f still rises there,
// or `start` (whose value is `at_start`) when nothing beats it; as (f, x).
template <typename Function>
std::pair<double, double> GoldenSectionMaximum(double lo_limit, double hi_limit, double start,
                                               double at_start, double tolerance, Function f) {
  const double inv_phi = (std::sqrt(5.0) - 1.0) / 2.0;  // 1/φ, the golden section
  double lo = lo_limit, hi = hi_limit;
  double x1 = hi - inv_phi * (hi - lo), x2 = lo + inv_phi * (hi - lo);
  double f1 = f(x1), f2 = f(x2);
  while (hi - lo > tolerance) {
    if (f1 > f2) {
      hi = x2;
      x2 = x1;
      f2 = f1;
      x1 = hi - inv_phi * (hi - lo);
      f1 = f(x1);
    } else {
      lo = x1;
      x1 = x2;
      f1 = f2;
      x2 = lo + inv_phi * (hi - lo);
      f2 = f(x2);
    }
  }
  std::array<std::pair<double, double>, 3> tried = {{{f1, x1}, {f2, x2}, {at_start, start}}};
  if (hi >= hi_limit - tolerance) tried[0] = {f(hi_limit), hi_limit};
  if (lo <= lo_limit + tolerance) tried[1] = {f(lo_limit), lo_limit};
  return *std::max_element(tried.begin(), tried.end());
}

}  // namespace insdiag::engine::numerics
