// Robust location and scale: the median, and the factor that makes a normal
// variable's median absolute deviation its σ (Hampel, J. Amer. Stat. Assoc.
// 69, 1974).
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace insdiag::engine::stats {

// 1/Φ⁻¹(0.75): a normal variable's median absolute deviation in its σ.
inline constexpr double kMadToSigma = 1.482602218505602;

// The median of `values` (the upper one of an even count), reordering them;
// `values` must not be empty.
inline double MedianInPlace(std::vector<double>& values) {
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

}  // namespace insdiag::engine::stats
