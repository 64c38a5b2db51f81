// Where the bench moved while its reference says it did not: a unit on a
// vehicle at rest that is knocked or rocks, a table a technician leans on.
// The reference (a still attitude, zero velocity, a fixed site) is then wrong
// by the bench's own motion, and the innovations there test the bench, not
// the unit; the monitor does not hold them against the unit
// (monitor/monitoring.h), and the report lists the stretches.
//
// The unit's own samples show it. Over each update interval, the scatter of
// each sensor channel's departure from the reference measurement (what a
// perfect unit would read, monitor/sample_screening.h) is compared with the
// channel's quiet level: the median of the intervals' log-variances, with
// 1.4826 × their median absolute deviation as its σ (a robust scale that a
// bench moving in a third of the intervals does not move; Hampel, J. Amer.
// Stat. Assoc. 69, 1974). The log of a sample variance is near normal where
// the variance itself is skewed, and a quantised channel's own spread is in
// the MAD. An interval whose standardised log-variance passes the
// family-wise normal quantile over the run's intervals and channels moved. A
// steady drift or a constant error changes a mean, not a scatter, so no
// catalogue effect of the unit (shared/spec/effects.md) shows here: only
// motion, or a sample spike the screening also reports.
//
// Only intervals over which the table's reference rate and specific force
// change by less than every channel's quiet σ are tested: where the table
// accelerates, a scale factor, misalignment or g-sensitivity of the change
// would add scatter of its own.
#pragma once

#include <array>
#include <vector>

#include "insdiag/engine/bench_run.h"

namespace insdiag::engine {

// A stretch of consecutive update intervals in which the bench moved.
struct BenchMotion {
  double start_s = 0.0;
  double end_s = 0.0;
  int sensor_channel = 0;  // the channel of the largest excess (kSensorChannelNames)
  double statistic = 0.0;  // that standardised excess of the scatter
};

// The stretches, in time order, over intervals of `update_interval_s`
// (at least two samples) from the run's first sample.
// `reference_measurements`: ReferenceMeasurements(run, …) (sample_screening.h).
std::vector<BenchMotion> FindBenchMotion(const BenchRun& run,
                                         const std::vector<std::array<double, 6>>& reference_measurements,
                                         double update_interval_s, double family_wise_alpha);

// Whether any stretch of `motion` (sorted) overlaps the interval (start_s, end_s].
bool BenchMovedWithin(const std::vector<BenchMotion>& motion, double start_s, double end_s);
// Whether a stretch of `motion` (sorted) holds the instant t_s, as the
// interval ending at it: start_s < t_s ≤ end_s.
bool BenchMovedAt(const std::vector<BenchMotion>& motion, double t_s);

}  // namespace insdiag::engine
