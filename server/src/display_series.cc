#include "insdiag/server/display_series.h"

#include <absl/strings/str_cat.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace insdiag::server {
namespace {

void Append(v1::ChannelEnvelope& out, double t, const SeriesEpoch& low, const SeriesEpoch& high, double band_low,
            double band_high) {
  out.add_t(t);
  out.add_measured_min(low.measured);
  out.add_measured_max(high.measured);
  out.add_predicted_min(low.predicted);
  out.add_predicted_max(high.predicted);
  out.add_residual_min(low.residual);
  out.add_residual_max(high.residual);
  out.add_sigma3_max(high.sigma3);
  out.add_band_low(band_low);
  out.add_band_high(band_high);
}

}  // namespace

absl::StatusOr<v1::ChannelEnvelope> DecimateForDisplay(std::span<const SeriesEpoch> epochs, double start_s,
                                                       double end_s, int columns) {
  if (columns < 1) return absl::InvalidArgumentError(absl::StrCat("columns must be at least 1, not ", columns));
  if (!std::isfinite(start_s) || !std::isfinite(end_s) || end_s < start_s) {
    return absl::InvalidArgumentError(
        absl::StrCat("the range [", start_s, ", ", end_s, "] s is not a finite interval that ends after it starts"));
  }
  const auto first = std::lower_bound(epochs.begin(), epochs.end(), start_s,
                                      [](const SeriesEpoch& e, double t) { return e.t < t; });
  const auto last = std::upper_bound(first, epochs.end(), end_s,
                                     [](double t, const SeriesEpoch& e) { return t < e.t; });
  const std::span<const SeriesEpoch> in_range(first, last);

  v1::ChannelEnvelope out;
  out.set_epochs(static_cast<std::int64_t>(in_range.size()));
  if (in_range.size() <= static_cast<std::size_t>(columns)) {
    for (const SeriesEpoch& e : in_range) {
      Append(out, e.t, e, e, e.predicted - e.sigma3, e.predicted + e.sigma3);
    }
    return out;
  }
  out.set_decimated(true);
  const double width = (end_s - start_s) / columns;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::size_t i = 0;
  while (i < in_range.size()) {
    // The column of epoch i; the last column keeps the range's end.
    const auto column = std::min<long>(static_cast<long>((in_range[i].t - start_s) / width), columns - 1);
    SeriesEpoch low{0, kInf, kInf, kInf, kInf};
    SeriesEpoch high{0, -kInf, -kInf, -kInf, -kInf};
    double band_low = kInf;
    double band_high = -kInf;
    for (; i < in_range.size(); ++i) {
      const SeriesEpoch& e = in_range[i];
      if (std::min<long>(static_cast<long>((e.t - start_s) / width), columns - 1) != column) break;
      low.measured = std::min(low.measured, e.measured);
      high.measured = std::max(high.measured, e.measured);
      low.predicted = std::min(low.predicted, e.predicted);
      high.predicted = std::max(high.predicted, e.predicted);
      low.residual = std::min(low.residual, e.residual);
      high.residual = std::max(high.residual, e.residual);
      high.sigma3 = std::max(high.sigma3, e.sigma3);
      band_low = std::min(band_low, e.predicted - e.sigma3);
      band_high = std::max(band_high, e.predicted + e.sigma3);
    }
    Append(out, start_s + (static_cast<double>(column) + 0.5) * width, low, high, band_low, band_high);
  }
  return out;
}

}  // namespace insdiag::server
