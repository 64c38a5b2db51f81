// The table encoders' readout noise, measured from the run's reference
// attitude itself.
//
// A readout r_k = θ(t_k) + e_k with white e of σ has second differences
// d_k = r_{k+1} − 2 r_k + r_{k−1} = θ'' Δt² + (e_{k+1} − 2 e_k + e_{k−1}),
// whose noise part has variance 6σ². The table's motion leaves d = 0 at rest
// and at a constant rate; only its rate changes (within one sample on most
// tables) add a few outliers, which a median ignores: σ̂ = 1.4826·med|d|/√6
// (Hampel, JASA 69(346), 1974, for the median absolute deviation as a
// consistent estimator of a Gaussian σ).
#pragma once

#include "insdiag/engine/bench_run.h"

namespace insdiag::engine::nav {

// σ̂ of the roll, pitch and yaw readouts together [rad]; 0 for a reference
// that reads exactly (a simulated table) or a run of fewer than three samples.
double AttitudeReadoutNoiseRad(const BenchRun& run);

}  // namespace insdiag::engine::nav
