// Faults at an onset where the unit turned and the reference did not say so.
//
// A bench that is knocked or a vehicle that rocks turns the unit by
// milliradians while its reference attitude stays constant. The gyros
// measure the turn and the strapdown follows it, but not exactly: vibration
// leaves a coning error in the attitude (Savage, "Strapdown inertial
// navigation integration algorithm design part 1", JGCD 21(1), 1998) and a
// lever arm moves the unit's position away from the reference's. Either
// shows in the navigation errors as a step of a sensor's bias would, and on
// a still unit an accelerometer's bias step and a tilt's jump are the same
// signature (δv̇ = g·δψ). The raw samples tell them apart: a sensor's step
// changes its own readings, the motion only turns gravity in them, which the
// gyros account for (Δf = −δθ × f̄, Titterton & Weston §3.6).
//
// So a step the onset scan finds inside a still segment, where the gyros'
// integrated rate turns across the onset beyond three standard errors of its
// noise, stands as a fault only if the raw samples across the onset —
// window means of `window_s` either side, accelerometers untilted — change
// significantly (|Δ|/SE beyond Φ⁻¹(1 − α/2)) and agree with the scan's
// estimate within the same bound. SE is the root mean square of the same
// difference at the stretch's other window positions. Otherwise the
// candidate is reported as not a finding of the unit, with what the raw
// samples show. Where the unit did not turn the check does not apply: a
// still unit's navigation errors have no other cause.
#pragma once

#include <optional>
#include <vector>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/finder/raw_sample_evidence.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/report.h"

namespace insdiag::engine::pipeline {

struct RawAcrossOnset {
  double window_s = 0.0;
  double turn_rad = 0.0;        // the largest axis' turn between the windows' mean angles
  bool turn_resolved = false;   // beyond kResolvedTurnStdErrors of its noise on some axis
  double jump = 0.0;            // the axis' mean after less before, in the family's unit
  double jump_std_error = 0.0;
};

// The gyros resolve a turn beyond this many standard errors of their angle
// noise over a window (a one-sided chance of 0.13 % per axis that noise
// alone reaches it).
inline constexpr double kResolvedTurnStdErrors = 3.0;

// The raw samples of `term`'s sensor axis across `onset_s`, where a still
// stretch of `raw` holds at least `window_s` / 4 either side (the windows
// shrink to what the stretch holds, up to `window_s`).
std::optional<RawAcrossOnset> RawSamplesAcrossOnset(const BenchRun& run, const RawSampleEvidence& raw,
                                                    const EffectTerm& term, double onset_s, double window_s);

// Applies the check above to the step candidates among `faults` (source GLR).
void WeighStepsWhereTheUnitTurned(std::vector<EffectCandidate>& faults, const BenchRun& run,
                                  const RawSampleEvidence& raw, double window_s, double alpha);

}  // namespace insdiag::engine::pipeline
