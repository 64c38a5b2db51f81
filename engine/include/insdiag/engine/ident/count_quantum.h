// The quantum of a counted output, read from the samples.
//
// A logger that reads an integrating counter — a ring-laser gyro's fringes, a
// pulse-rebalanced accelerometer's charge pulses, an IMU's accumulated
// increments — gives each sample as a whole number of quanta q [rad | m/s]
// over its interval; the counter keeps the sub-quantum remainder, so the
// integrated output differs from the true integral by a remainder bounded by
// one quantum, uniform over it when the input carries the count across many
// quanta: variance Q² = q²/12 (IEEE Std 952-1997, Annex C; Savage, Strapdown
// Analytics, 2nd ed., §19.4). That is the quantisation term of the error
// model (error_model.h), and the samples give q itself: every increment
// ω_k·Δt (f_k·Δt) lies on the lattice of q.
//
// Why read q rather than take Q from the Allan curve. The curve's √3 Q/τ
// branch holds only where the counter's remainder moves at random from
// sample to sample (IEEE Std 952, C.1). A navigation-grade unit at rest reads
// a nearly constant count (an accelerometer along gravity reads 125 quanta a
// sample, its white noise a few hundredths of one): the remainder then turns
// slowly as a saw-tooth and the curve's short-τ branch falls below √3 Q/τ,
// while the velocity the filter observes still carries the whole remainder.
#pragma once

#include <array>
#include <optional>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/model/drift_axis.h"

namespace insdiag::engine::ident {

struct CountQuantumOptions {
  // The lattice is read from at most this many samples, then checked on all.
  size_t max_samples_read = 200'000;
  // A sample lies on the lattice when its count is within this of a whole
  // number: far above the rounding of a count in double precision, far
  // below the fraction a continuous output would show.
  double count_tolerance = 1e-6;
  // A counted output repeats its values: at most this share of the samples
  // read are distinct (a continuous output's are nearly all distinct).
  double max_distinct_share = 0.25;
};

// q [rad | m/s] of each sensor axis of `run`'s samples (DriftAxis::Index
// order), each sample read as its increment over the run's nominal interval;
// nullopt where the samples do not lie on one lattice (a single value lies
// on its sensor's other axes' lattice, or on none). The smallest spacing of
// the sensor's three axes is tried first on each axis (two values two quanta
// apart would otherwise read as one quantum), then the axis' own.
std::array<std::optional<double>, DriftAxis::kCount> CountQuanta(const BenchRun& run,
                                                                 const CountQuantumOptions& options = {});

}  // namespace insdiag::engine::ident
