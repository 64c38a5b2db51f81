// What the raw samples of a run's still segments show of each sensor axis,
// needing no navigation model. There the table holds the body at a known
// attitude and a perfect unit's reading is known (ident/static_constants.h);
// what the unit reads beyond it is the sensor's own.
//
// Changes. A jump of a still segment's rate or a ramp of it (ident/allan.h:
// jumps and ramps) is a fault the navigation errors may not tell from a
// look-alike (fault_findings.h, IsLikelierLookAlike). Each is a finding of
// its own (fault_findings.h, AddRawSampleFaultCandidates): a ramp's test's
// null is a rate random walk, the noise of the largest Allan-to-Hadamard
// ratio, so no noise of the model passes it more often than its level; a
// jump's is held to the Bonferroni bound over its window positions.
//
// Constants. The mean of the reading minus the perfect unit's over the still
// samples measures each axis' constant bias, b̂ ± SE_raw. The navigation
// errors see a gyro's constant bias only through what it does to the
// attitude, a vertical gyro's through gyrocompassing: a slow rise of the
// horizontal velocity errors that any unmodelled slow change there imitates.
// On a still table an accelerometer's ramp is explained almost as well by a
// vertical gyro bias many times the raw samples' bound on it. A
// constant-bias candidate (a family of regressor kOne) whose one-step
// estimate β̂ ± SE disagrees with the raw samples',
//   |β̂ − b̂| / √(SE² + SE_raw²) > Φ⁻¹(1 − α / 2m)
// (two-sided, Bonferroni over the m axes compared), is refuted: its signature
// in the navigation errors comes from another effect, and it is reported so,
// not ranked. Both estimates take the same drift's realisation in part, so
// the variance of their difference is at most the sum: the test refutes less
// often than its level says.
//
// The raw mean holds every deterministic effect of the sensor that acts on a
// still unit. It measures the same constant as a candidate only on a model
// that holds no deterministic effect of that sensor (RawConstantsComparable).
#pragma once

#include <span>
#include <string>
#include <vector>

#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/model/error_model.h"

namespace insdiag::engine {

// A change the raw samples of one sensor axis show in the run's static
// segments: a jump of the rate's mean (kStep, `size` in the family's unit)
// or a ramp (kRamp, `size` its slope), as the Allan analysis finds them
// (ident/allan.h: Jumps, Ramps). `tolerance_s`: how closely its time is
// placed.
struct RawSampleChange {
  Sensor sensor = Sensor::kGyro;
  int axis = 0;
  Regressor shape = Regressor::kStep;
  double time_s = 0.0;
  double size = 0.0;
  double tolerance_s = 0.0;
  // The channel's test: P(a change this clear | no change), before any
  // correction over the channels.
  double p_value = 1.0;
  // A jump's standard error from the samples: s_w, the scatter of the
  // difference of adjacent window means away from it (ident/allan.h, Jumps).
  // A ramp's comes from the model's noise (fault_findings.h).
  double std_error = 0.0;
};

// One sensor axis' constant bias over the still samples, in its turn-on
// bias family's unit (ident/static_constants.h).
struct RawSampleConstant {
  Sensor sensor = Sensor::kGyro;
  int axis = 0;
  double bias = 0.0;
  double std_error = 0.0;
};

// A still segment's samples of the run, [first_sample, end_sample).
struct StillStretch {
  std::size_t first_sample = 0;
  std::size_t end_sample = 0;
};

struct RawSampleEvidence {
  std::vector<RawSampleChange> changes;
  std::vector<RawSampleConstant> constants;  // none when the run has no still segment
  // The still segments and their sample interval, for a look at the raw
  // samples across a step's onset (analysis/steps_in_raw_samples.h).
  std::vector<StillStretch> still;
  double sample_interval_s = 0.0;
};

// The constants of `evidence` that measure what a candidate of `model` would:
// those of the sensors `model` holds no constant or fault effect of.
std::vector<RawSampleConstant> RawConstantsComparable(const RawSampleEvidence& evidence,
                                                      const ErrorModel& model);

// Whether the raw samples' constants refute the constant-bias term `term`
// estimated at `estimate` ± `std_error` (above); false for any other term or
// where no constant of its axis is given. `note` receives what they say.
bool RefutedByRawSamples(const EffectTerm& term, double estimate, double std_error,
                         std::span<const RawSampleConstant> constants, double family_wise_alpha,
                         std::string* note);

}  // namespace insdiag::engine
