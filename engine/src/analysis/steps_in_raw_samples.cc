#include "analysis/steps_in_raw_samples.h"

#include <absl/strings/str_format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <string>

#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine::pipeline {
Eigen::Vector3d RawWindows::TiltChange() const { return -turn_rad.cross(force_before); }

RawWindows RawWindowsAcross(const BenchRun& run, std::size_t j, std::size_t w, const Eigen::Vector3d& mean_rate,
                            double tau0_s) {
  RawWindows out;
  Eigen::Vector3d angle = Eigen::Vector3d::Zero(), angle_before = Eigen::Vector3d::Zero(),
                  angle_after = Eigen::Vector3d::Zero(), gyro_before = Eigen::Vector3d::Zero(),
                  gyro_after = Eigen::Vector3d::Zero(), acc_after = Eigen::Vector3d::Zero();
  for (std::size_t i = j - w; i < j + w; ++i) {
    const ImuSample& s = run.samples[i];
    angle += (s.gyro_rad_s - mean_rate) * tau0_s;
    if (i < j) {
      angle_before += angle;
      gyro_before += s.gyro_rad_s;
      out.force_before += s.acc_mps2;
    } else {
      angle_after += angle;
      gyro_after += s.gyro_rad_s;
      acc_after += s.acc_mps2;
    }
  }
  const double n = static_cast<double>(w);
  out.turn_rad = (angle_after - angle_before) / n;
  out.gyro_change = (gyro_after - gyro_before) / n;
  out.acc_change = (acc_after - out.force_before) / n;
  out.force_before /= n;
  return out;
}

Eigen::Vector3d MeanGyroRate(const BenchRun& run, std::size_t first, std::size_t end) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (std::size_t i = first; i < end; ++i) sum += run.samples[i].gyro_rad_s;
  return sum / static_cast<double>(end - first);
}

std::size_t FirstSampleAfter(const BenchRun& run, double t_s) {
  const auto at = std::upper_bound(run.samples.begin(), run.samples.end(), t_s,
                                   [](double t, const ImuSample& s) { return t < s.t_s; });
  return static_cast<std::size_t>(at - run.samples.begin());
}

namespace {

// The difference of one sensor axis' window means across sample j; an
// accelerometer's untilted, less the change the turn between the windows
// makes of gravity in it.
double AcrossSample(const BenchRun& run, std::size_t j, std::size_t w, const Eigen::Vector3d& mean_rate,
                    double tau0_s, Sensor sensor, int axis) {
  const RawWindows windows = RawWindowsAcross(run, j, w, mean_rate, tau0_s);
  return sensor == Sensor::kGyro ? windows.gyro_change[axis]
                                 : windows.acc_change[axis] - windows.TiltChange()[axis];
}

}  // namespace

std::optional<RawAcrossOnset> RawSamplesAcrossOnset(const BenchRun& run, const RawSampleEvidence& raw,
                                                    const EffectTerm& term, double onset_s, double window_s) {
  const double tau0_s = raw.sample_interval_s;
  if (run.samples.empty() || !(tau0_s > 0.0) || !(window_s > 0.0)) return std::nullopt;
  const std::size_t k = FirstSampleAfter(run, onset_s);
  const auto stretch = std::find_if(raw.still.begin(), raw.still.end(), [&](const StillStretch& s) {
    return s.first_sample < k && k < s.end_sample;
  });
  if (stretch == raw.still.end()) return std::nullopt;
  const auto widest = static_cast<std::size_t>(std::lround(window_s / tau0_s));
  const std::size_t w = std::min({widest, k - stretch->first_sample, stretch->end_sample - k});
  if (w < 2 || 4 * w < widest) return std::nullopt;
  const Eigen::Vector3d mean_rate = MeanGyroRate(run, stretch->first_sample, stretch->end_sample);
  const Sensor sensor = term.family->sensor;
  const double centre = AcrossSample(run, k, w, mean_rate, tau0_s, sensor, term.axis);
  // The same difference at the stretch's other positions, two windows or
  // more from the onset, gives its standard error.
  double sum_squares = 0.0;
  int positions = 0;
  for (std::size_t j = stretch->first_sample + w; j + w <= stretch->end_sample; j += w) {
    if (j + 2 * w > k && j < k + 2 * w) continue;
    const double d = AcrossSample(run, j, w, mean_rate, tau0_s, sensor, term.axis);
    sum_squares += d * d;
    ++positions;
  }
  constexpr int kFewestPositions = 4;  // fewer say too little of the scatter
  if (positions < kFewestPositions) return std::nullopt;
  RawAcrossOnset out;
  out.window_s = static_cast<double>(w) * tau0_s;
  out.jump = centre;
  out.jump_std_error = std::sqrt(sum_squares / positions);
  return out;
}

void WeighStepsByTheirRawSamples(std::vector<EffectCandidate>& faults, const BenchRun& run,
                                 const RawSampleEvidence& raw, double window_s, double alpha) {
  const double z = stats::NormalQuantile(1.0 - alpha / 2.0);
  for (EffectCandidate& c : faults) {
    if (c.source != "GLR" || !c.identifiable || !c.onset_s.has_value()) continue;
    const auto terms = ParseEffectSelector(c.name);
    if (!terms.ok() || terms->size() != 1) continue;
    const EffectTerm& term = terms->front();
    if (term.family->regressor != Regressor::kStep) continue;
    const auto across = RawSamplesAcrossOnset(run, raw, term, *c.onset_s, window_s);
    if (!across.has_value()) continue;
    const bool shows = std::abs(across->jump) > z * across->jump_std_error;
    const bool agrees = std::abs(c.estimate - across->jump) <= z * std::hypot(across->jump_std_error, c.std_error);
    const std::string what = absl::StrFormat(
        "its raw samples over %.0f s either side of %.0f s%s change by %.3g ± %.2g %s", across->window_s,
        *c.onset_s, term.family->sensor == Sensor::kAccelerometer ? ", untilted by the turn the gyros measured," : "",
        across->jump, across->jump_std_error, c.unit);
    if (shows && agrees) {
      c.seen_in_raw_samples = true;
      c.note += "; " + what;
      continue;
    }
    c.identifiable = false;
    c.note = what + (shows ? ", not the step's size" : ", no more than their scatter elsewhere in the stretch") +
             ": not a change of the sensor the samples show (a knock or a rocking mount turns the unit as a "
             "step would seem to); " + c.note;
  }
}

}  // namespace insdiag::engine::pipeline
