// Jumps in the mean of a static segment's rate (allan.h: Jumps).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "insdiag/engine/ident/allan.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine::ident {
namespace {

constexpr int64_t kFirstWindowSamples = 4;
constexpr int64_t kWindowGrowth = 4;

// The windows tested in a series of n samples: 4, 16, 64, … while n holds
// `min_windows` of them.
std::vector<int64_t> JumpWindows(int64_t n, int min_windows) {
  std::vector<int64_t> windows;
  for (int64_t w = kFirstWindowSamples; w * min_windows <= n; w *= kWindowGrowth)
    windows.push_back(w);
  return windows;
}

// The largest |d_w(k)| at window w and its z against the rest of d_w.
// `sum` holds the prefix sums of the series less its first value (sum[k] = Σ_{i<k} (y_i − y_0)).
RateJump LargestAtWindow(const std::vector<double>& sum, int64_t w) {
  const auto n = static_cast<int64_t>(sum.size()) - 1;
  const auto d = [&](int64_t k) {
    const auto at = [&](int64_t i) { return sum[static_cast<size_t>(i)]; };
    return ((at(k + w) - at(k)) - (at(k) - at(k - w))) / static_cast<double>(w);
  };
  RateJump best;
  best.window = w;
  double all_squares = 0.0;
  for (int64_t k = w; k <= n - w; ++k) {
    const double v = d(k);
    all_squares += v * v;
    if (std::abs(v) > std::abs(best.size)) {
      best.size = v;
      best.sample = static_cast<size_t>(k);
    }
  }
  // The scale from the differences that do not straddle the candidate.
  const auto k0 = static_cast<int64_t>(best.sample);
  double near_squares = 0.0;
  int64_t near = 0;
  for (int64_t k = std::max(w, k0 - w + 1); k <= std::min(n - w, k0 + w - 1); ++k, ++near)
    near_squares += d(k) * d(k);
  const double rest = static_cast<double>(n - 2 * w + 1 - near);
  const double scale_squared = (all_squares - near_squares) / rest;
  best.z = rest > 0.0 && scale_squared > 0.0 ? std::abs(best.size) / std::sqrt(scale_squared) : 0.0;
  return best;
}

// Whether a jump of d_w(k) = `size` persists: the means of `span` samples
// on either side, beyond w samples from k, differ by at least half of it
// with its sign. A transient (a spike, a knock on the table, a start-up
// settling) moves d_w near it as a step does, and leaves the means over a
// segment's length alone.
bool Persists(const std::vector<double>& sum, int64_t k, int64_t w, int64_t span, double size) {
  const auto n = static_cast<int64_t>(sum.size()) - 1;
  if (k - w - span < 0 || k + w + span > n) return false;
  const auto at = [&](int64_t i) { return sum[static_cast<size_t>(i)]; };
  const double after = (at(k + w + span) - at(k + w)) / static_cast<double>(span);
  const double before = (at(k - w) - at(k - w - span)) / static_cast<double>(span);
  return (after - before) * size >= 0.5 * size * size;
}

void CutInto(std::span<const double> rates, size_t offset, double tau0_s,
             const AllanOptions& options, std::vector<RatePiece>& pieces,
             std::vector<RateJump>* jumps) {
  const std::optional<RateJump> jump = FindRateJump(rates, tau0_s, options);
  if (!jump.has_value()) {
    pieces.push_back({offset, offset + rates.size()});
    return;
  }
  CutInto(rates.first(jump->sample), offset, tau0_s, options, pieces, jumps);
  if (jumps != nullptr) {
    RateJump in_whole = *jump;
    in_whole.sample += offset;
    jumps->push_back(in_whole);
  }
  CutInto(rates.subspan(jump->sample), offset + jump->sample, tau0_s, options, pieces, jumps);
}

}  // namespace

std::optional<RateJump> FindRateJump(std::span<const double> rates, double tau0_s,
                                     const AllanOptions& options) {
  const auto n = static_cast<int64_t>(rates.size());
  const auto span = static_cast<int64_t>(options.MinSegmentSamples(tau0_s));
  const std::vector<int64_t> windows = JumpWindows(n, options.jump_min_windows);
  if (windows.empty() || !(options.jump_alpha > 0.0)) return std::nullopt;
  double positions = 0.0;  // J: every position of every window
  for (int64_t w : windows) positions += static_cast<double>(n - 2 * w + 1);
  const double z_bound = stats::NormalQuantile(1.0 - options.jump_alpha / (2.0 * positions));

  // Prefix sums of the series less its first value: the sums stay of the
  // noise's size, not of n times the rate's (g on a vertical accelerometer).
  std::vector<double> sum(rates.size() + 1, 0.0);
  for (size_t i = 0; i < rates.size(); ++i) sum[i + 1] = sum[i] + (rates[i] - rates[0]);
  std::optional<RateJump> best;
  for (int64_t w : windows) {
    const RateJump at_w = LargestAtWindow(sum, w);
    if (at_w.z > z_bound && (!best.has_value() || at_w.z > best->z) &&
        Persists(sum, static_cast<int64_t>(at_w.sample), w, span, at_w.size)) {
      best = at_w;
    }
  }
  if (best.has_value()) {
    best->p_value = std::min(1.0, positions * stats::ChiSquareSurvival(best->z * best->z, 1.0));
  }
  return best;
}

std::vector<RatePiece> CutAtRateJumps(std::span<const double> rates, double tau0_s,
                                      const AllanOptions& options, std::vector<RateJump>* jumps) {
  std::vector<RatePiece> pieces;
  CutInto(rates, 0, tau0_s, options, pieces, jumps);
  return pieces;
}

}  // namespace insdiag::engine::ident
