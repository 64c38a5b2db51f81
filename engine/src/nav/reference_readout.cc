#include "insdiag/engine/nav/reference_readout.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "insdiag/engine/stats/robust.h"

namespace insdiag::engine::nav {
namespace {

constexpr double kSecondDifferenceVarianceFactor = 6.0;  // Var(e₊ − 2e + e₋) = 6σ²

}  // namespace

double AttitudeReadoutNoiseRad(const BenchRun& run) {
  const auto& s = run.samples;
  if (s.size() < 3) return 0.0;
  std::vector<double> magnitudes;
  magnitudes.reserve(3 * (s.size() - 2));
  for (size_t k = 1; k + 1 < s.size(); ++k) {
    // A multi-position test's unrecorded moves are not readout noise.
    if (run.StartsSegment(k) || run.StartsSegment(k + 1)) continue;
    for (int i = 0; i < 3; ++i) {
      const double ahead = std::remainder(s[k + 1].ref_rpy_rad[i] - s[k].ref_rpy_rad[i], 2.0 * std::numbers::pi);
      const double behind = std::remainder(s[k].ref_rpy_rad[i] - s[k - 1].ref_rpy_rad[i], 2.0 * std::numbers::pi);
      magnitudes.push_back(std::abs(ahead - behind));
    }
  }
  if (magnitudes.empty()) return 0.0;
  return stats::kMadToSigma * stats::MedianInPlace(magnitudes) / std::sqrt(kSecondDifferenceVarianceFactor);
}

}  // namespace insdiag::engine::nav
