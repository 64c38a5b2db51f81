// A bias step found inside a still stretch stands as a fault only where the
// sensor's raw samples show it.
//
// On a unit at rest the navigation errors see an accelerometer's bias step
// as they see a tilt's jump (δv̇ = g·δψ), and a gyro's as they see a slow
// turn; a bench that is knocked or a vehicle that rocks makes both without
// any change of the sensor: vibration leaves a coning error in the
// strapdown's attitude (Savage, "Strapdown inertial navigation integration
// algorithm design part 1", JGCD 21(1), 1998) and a lever arm moves the unit
// away from the reference's position. The raw samples of a still stretch
// tell the sensor's change from the motion's: a sensor's step changes its own
// readings, a turn only turns gravity in them, which the gyros account for
// (Δf = −δθ × f̄, Titterton & Weston §3.6).
//
// So across the onset of every step the onset scan finds inside a still
// stretch, the window means of the sensor axis' raw samples, `window_s`
// either side (accelerometers untilted by the turn the gyros measured
// between the windows), must change by more than Φ⁻¹(1 − α/2) standard
// errors and agree with the scan's estimate within the same bound. The
// standard error is the root mean square of the same difference at the
// stretch's other window positions: the scatter the stretch's noise, drift
// and motion give such a difference. Otherwise the candidate is reported as
// not a finding, with what the raw samples show. A step during the table's
// motion, or in a stretch too short to hold four other positions, is not
// checked: its raw samples say nothing the navigation errors do not.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <optional>
#include <vector>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/finder/raw_sample_evidence.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/report.h"

namespace insdiag::engine::pipeline {

// The raw samples either side of sample j of a still stretch: over
// [j − w, j) and [j, j + w), the change of the gyros' and accelerometers'
// window means, the turn between the windows' mean angles (the gyros' rate
// less `mean_rate` — Earth's rate and the biases over the stretch —
// integrated from j − w), and the force's mean before. A turn δθ changes a
// still unit's reading of gravity by Δf = −δθ × f̄ (Titterton & Weston
// §3.6), a change of the samples but not of the sensor: TiltChange.
struct RawWindows {
  Eigen::Vector3d gyro_change = Eigen::Vector3d::Zero();
  Eigen::Vector3d acc_change = Eigen::Vector3d::Zero();
  Eigen::Vector3d turn_rad = Eigen::Vector3d::Zero();
  Eigen::Vector3d force_before = Eigen::Vector3d::Zero();

  Eigen::Vector3d TiltChange() const;
};
RawWindows RawWindowsAcross(const BenchRun& run, std::size_t j, std::size_t w, const Eigen::Vector3d& mean_rate,
                            double tau0_s);

// The gyros' mean rate over samples [first, end) of `run`.
Eigen::Vector3d MeanGyroRate(const BenchRun& run, std::size_t first, std::size_t end);

// The index of the first sample of `run` after `t_s`.
std::size_t FirstSampleAfter(const BenchRun& run, double t_s);

struct RawAcrossOnset {
  double window_s = 0.0;
  double jump = 0.0;  // the axis' mean after less before, in the family's unit
  double jump_std_error = 0.0;
};

// The raw samples of `term`'s sensor axis across `onset_s`, where a still
// stretch of `raw` holds at least `window_s` / 4 either side (the windows
// shrink to what the stretch holds, up to `window_s`) and four other window
// positions.
std::optional<RawAcrossOnset> RawSamplesAcrossOnset(const BenchRun& run, const RawSampleEvidence& raw,
                                                    const EffectTerm& term, double onset_s, double window_s);

// Applies the check above to the step candidates among `faults` (source GLR).
void WeighStepsByTheirRawSamples(std::vector<EffectCandidate>& faults, const BenchRun& run,
                                 const RawSampleEvidence& raw, double window_s, double alpha);

}  // namespace insdiag::engine::pipeline
