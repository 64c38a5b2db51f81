// What a run's first samples say of each sensor's bias at its start: the
// spread the filter's drift states start with.
//
// The base model's drift is a first-order Gauss–Markov process in its
// stationary distribution, so the filter starts each drift state at N(0, σ²)
// (seed paper eq. 5–6). A unit switched on for the test is not there yet:
// its die warms by kelvins over its first minutes and the bias settles with
// it (IEEE Std 952-1997, §B.8 "warm-up"; a MEMS part's settles by tenths of a
// degree per second and milli-g). Against a stationary prior such a start is
// an outlier of many σ in the first seconds, and a gradual failure after.
//
// The samples measure it. While the table holds the body still at its start,
// a perfect unit reads Earth's rate and gravity in the reference attitude
// (static_constants.h); the reading's mean over a window W at the start,
// less its mean over the whole still stretch, is the bias's departure d at
// the start from its level over the stretch (a level error of the reference
// is the same in both and cancels). The window's own noise is
// s² = N²/W + 2Q²/W² (white noise of density N; a counter's residue at the
// window's two ends, Q the quantisation; IEEE Std 952-1997, Annex C), so
// d² − s² estimates the square of the bias's start value. Each drift state
// starts with the larger of its stationary σ² and that estimate: the
// empirical-Bayes start of a state whose stationarity the run does not
// grant (Durbin & Koopman, Time Series Analysis by State Space Methods,
// 2nd ed., §5.1, for the diffuse limit it stops short of). On a stationary
// start d² − s² scatters about σ² (χ² with one degree of freedom), so the
// prior widens only by a few σ² where it widens at all; a warm-up of many σ
// starts where the samples put it, and no alarm comes from it.
//
// W resolves the drift: it is where the window's white noise falls to the
// stationary σ, N²/σ², and at least one update interval. A start where the
// bench moved (monitor/bench_motion.h) measures the bench, not the bias: a
// window is measured only where it ends a window's length before the bench
// first moved, for a tilt that a vehicle settles into shows in the means
// before the scatter shows the motion.
#pragma once

#include <array>
#include <optional>

#include <Eigen/Core>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/model/error_model.h"

namespace insdiag::engine {

struct StartDeparture {
  // Per sensor axis (gyro x, y, z, accelerometer x, y, z): the square of the
  // bias's start value the samples estimate, d² − s² (0 where it is negative
  // or the axis was not measured). rad²/s² | m²/s⁴.
  std::array<double, kSensorAxisCount> start_square{};
  // The departure measured, its window and its standard error, for every axis
  // the still start could measure (window 0 where it could not).
  std::array<double, kSensorAxisCount> departure{};
  std::array<double, kSensorAxisCount> window_s{};
  std::array<double, kSensorAxisCount> std_error{};
};

using Vector6d = Eigen::Matrix<double, 6, 1>;

// The run's still start: the samples from the first while the reference
// attitude stays within `still_tolerance_rad` of the first sample's and no
// new segment begins. Returns their end (exclusive).
size_t StillStartEnd(const BenchRun& run, double still_tolerance_rad);

// What a perfect unit reads at rest in the run's first reference attitude
// (static_constants.h): Earth's rate, then gravity's specific force, in body
// axes. The run must have a sample.
Vector6d PerfectReadingAtStart(const BenchRun& run);

// Measures the start's departure on `run`'s samples with `model`'s noise and
// drift, the reference still within `still_tolerance_rad` (StillToleranceRad)
// and the bench moving from `bench_moved_from_s` (none: not in the run); none
// (all zeros) where the run does not start still or its still, quiet start
// is shorter than two of an axis's windows.
StartDeparture MeasureStartDeparture(const BenchRun& run, const ErrorModel& model, double update_interval_s,
                                     double still_tolerance_rad, std::optional<double> bench_moved_from_s);

}  // namespace insdiag::engine
