// Screening of the raw samples for spikes: isolated samples that depart from
// their neighbours far beyond the sensor's noise (a transmission error, a
// momentary electronic fault). A spike integrates into a step of attitude or
// velocity that no sensor model explains, so it is flagged as an outlier and
// replaced before the mechanisation, and the estimates after it stay clean.
//
// The test runs on r_k = x_k − x̂_k, the departure of each sample from what a
// perfect unit would have measured given the table's reference attitude (body
// rate and gravity turning with the body), so the table's motion is never
// taken for a spike. A sample is a spike when |r_k − med_k| > threshold · σ,
// where med_k is the median of the 2w+1 departures around k and
// σ = 1.4826 · median |r − med| over the channel (a robust standard deviation;
// Hampel, J. Amer. Stat. Assoc. 69, 1974 — the "Hampel identifier"), or, when
// larger, the 90th percentile of |r − med| / 1.6449, the same σ for Gaussian
// noise: on coarsely quantised samples most departures are zero (or timing
// jitter), the median collapses, and every quantum step would be a spike.
#pragma once

#include <array>
#include <string_view>
#include <vector>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/nav/table_motion.h"

namespace insdiag::engine {

// Raw sensor channels in sample order: gyro x, y, z, then accelerometer x, y, z.
inline constexpr std::string_view kSensorChannelNames[6] = {"gyro_x", "gyro_y", "gyro_z",
                                                            "acc_x",  "acc_y",  "acc_z"};

struct ScreeningOptions {
  int half_window = 5;      // w
  double threshold = 12.0;  // in robust standard deviations
};

struct SampleOutlier {
  size_t sample = 0;
  int sensor_channel = 0;  // index into kSensorChannelNames
  double time_s = 0.0;
  double robust_z = 0.0;
  double value = 0.0;        // as recorded
  double replacement = 0.0;  // the neighbours' median used instead
};

// What a perfect unit would have measured over each sample's interval given
// the table's reference attitude at the site: the body rate (with Earth's)
// and the specific force, gyro x, y, z then accelerometer x, y, z; sample 0
// takes sample 1's. `compensations`: the run's (nav/table_motion.h).
std::vector<std::array<double, 6>> ReferenceMeasurements(const BenchRun& run,
                                                         const nav::RunCompensations& compensations);

// Finds spikes and replaces them in `run` (in place), against
// `reference_measurements` = ReferenceMeasurements(run, …) when the caller has it.
std::vector<SampleOutlier> ScreenAndRepairSpikes(BenchRun& run,
                                                 const std::vector<std::array<double, 6>>& reference_measurements,
                                                 const ScreeningOptions& options);
std::vector<SampleOutlier> ScreenAndRepairSpikes(BenchRun& run, const ScreeningOptions& options);

}  // namespace insdiag::engine
