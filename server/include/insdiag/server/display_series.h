// Decimation of a residual series for display (ReadDisplaySeries): a plot
// `columns` pixels wide shows at most one vertical stroke per column, so the
// epochs of each column are reduced to their extremes. A spike of one epoch
// still reaches its full height, which averaging or picking every n-th epoch
// would hide; and the answer's size depends on the plot's width, not on the
// run's length.
#pragma once

#include <absl/status/statusor.h>

#include <span>

#include "insdiag/v1/analyses.pb.h"

namespace insdiag::server {

// One epoch of one channel, as the series store holds it (sigma3 = 3σ).
struct SeriesEpoch {
  double t = 0;
  double measured = 0;
  double predicted = 0;
  double residual = 0;
  double sigma3 = 0;
};

// The envelope of `epochs` (in time order) over [start_s, end_s], ends
// included, cut into `columns` equal columns; each non-empty column gives one
// entry at its centre. When the range holds no more epochs than columns, the
// epochs themselves (decimated = false). Only `channel` is left for the caller.
// INVALID_ARGUMENT for columns < 1, a range that is not finite or ends before it starts.
absl::StatusOr<v1::ChannelEnvelope> DecimateForDisplay(std::span<const SeriesEpoch> epochs, double start_s,
                                                       double end_s, int columns);

}  // namespace insdiag::server
