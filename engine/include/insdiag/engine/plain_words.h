// The verdict in plain words: the few lines a quality engineer reads first —
// what is wrong, where, how sure, what to do — before the tables and the
// engine's notes. Each finding says what the raw samples show around it (a
// step: the sensor's minute means either side of its onset), so that a
// person can check it without the model.
#pragma once

#include <Eigen/Core>
#include <span>
#include <string>
#include <vector>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/monitor/sample_screening.h"
#include "insdiag/engine/report.h"

namespace insdiag::engine {

// At most this many lines: the verdict, up to three findings, what to do.
inline constexpr int kPlainWordsMaxLines = 5;

// The samples as the unit recorded them, read from the run the analysis
// worked on: the spikes its screening repaired and the dominant constants it
// removed before identification are put back, so that an analysis keeps one
// copy of the run, not two (a 1M-sample run is 88 MB).
struct RecordedSamples {
  const BenchRun& worked_on;
  Eigen::Vector3d removed_gyro_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d removed_acc_mps2 = Eigen::Vector3d::Zero();
  std::span<const SampleOutlier> repaired_spikes;  // each with its value as recorded

  // The recorded mean of sensor channel `channel` (bench_run.h's
  // SensorChannelValue order) over [from_s, to_s); NaN where no sample lies.
  double Mean(int channel, double from_s, double to_s) const;
};

// The report's verdict in plain words, quoting the samples as recorded.
std::vector<std::string> PlainWordsVerdict(const AnalysisReport& report, const RecordedSamples& samples,
                                           double family_wise_alpha);
// The same where `run` is as recorded.
std::vector<std::string> PlainWordsVerdict(const AnalysisReport& report, const BenchRun& run,
                                           double family_wise_alpha);

}  // namespace insdiag::engine
