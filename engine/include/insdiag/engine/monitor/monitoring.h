// Functional monitoring of the bench run, as in the seed (monitoring section):
// channel-wise tests of the normalised residuals, fault intervals, the
// good / operable / faulty verdict, and localisation of a trouble to a sensor.
//
//   β²_j = ν_j² / α_j²  ~ χ²(1) per scalar update;  tolerance γ² = 1 + 3√2 ≈ 5.24
//   F_j = Σ_W ν² / Σ_W α²  over a moving window of W updates: the ratio of the
//         actual to the predicted residual variance, mean a = 1 and variance
//         2b with b = 1/W under the model; tolerance η² = a + 3√(2b)
//
// A single β² above γ² happens by chance in 2.2% of updates, and the moving F
// above η² in a fraction of windows, so fault intervals are only reported
// where the statistics exceed their family-wise (1 − α) quantiles over the
// run's updates (OUTLIER) or the tests the overlapping windows amount to
// (GRADUAL, a scan statistic's count, monitoring.cc); the counts against
// the seed's own tolerances are reported per channel beside them.
//
// Verdict: FAULTY when a gradual failure is found; OPERABLE when only outliers
// are found or the mean NIS leaves its χ² band; GOOD otherwise. The three
// families of tests share the family-wise α equally (Bonferroni), so a unit
// whose model holds is judged GOOD with probability ≥ 1 − α.
//
// Localisation: for each gradual failure, the sensor state whose jump best
// explains the innovations after its onset (monitor/fault_localisation.h);
// beside it, the seed's forward/backward discrepancy d_i (filter/smoother.h)
// of each sensor state against its family-wise χ²(1) quantile over the epochs.
#pragma once

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "insdiag/engine/filter/forward_filter.h"
#include "insdiag/engine/filter/smoother.h"
#include "insdiag/engine/model/state_layout.h"
#include "insdiag/engine/monitor/bench_motion.h"
#include "insdiag/engine/monitor/fault_localisation.h"
#include "insdiag/engine/monitor/sample_screening.h"

namespace insdiag::engine {

enum class Verdict { kGood, kOperable, kFaulty };
// kAbrupt: a bias step found by the onset scan (finder/onset_scan.h); a
// ramp found there is kGradual.
enum class FaultKind { kOutlier, kGradual, kAbrupt };

struct FaultInterval {
  std::string channel;  // observation channel ("vel_n") or raw sensor channel ("gyro_x")
  double start_s = 0.0;
  double end_s = 0.0;
  FaultKind kind = FaultKind::kOutlier;
  double peak_statistic = 0.0;  // β², F or the spike's robust z
};

struct ChannelFit {
  std::string name;
  std::string unit;
  int count = 0;
  double rms = 0.0;              // of the residuals ν
  double fit_percent = 0.0;      // 100 (1 − ‖z − ẑ‖ / ‖z − mean z‖)
  double nis_mean = 0.0;         // mean β²
  double whiteness_p_value = 0.0;  // Ljung–Box on ν/α
  double fraction_over_gamma2 = 0.0;  // share of updates with β² > γ² (2.2% expected)
  double fraction_over_eta2 = 0.0;    // share of windows with F > η²
};

// A sensor state named as the seat of a failure.
struct Localisation {
  std::string state;  // e.g. "gyro_bias_gm.x"
  double time_s = 0.0;     // the jump's onset, or the discrepancy's peak
  double statistic = 0.0;  // ℓ of the jump, or d_i at its peak
  double p_value = 0.0;    // family-wise
  // "JUMP" (likelihood ratio of a state's jump), "FORWARD_BACKWARD"
  // (discrepancy), "GLR" (a fault effect's onset scan, or its estimate in
  // a model that holds it) or "RAW" (a jump or ramp the still segments' raw
  // samples show)
  std::string method;
  double jump = 0.0;       // the jump's estimate in the state's unit (JUMP only)
  double jump_std_error = 0.0;
};

struct MonitorOptions {
  double window_s = 60.0;
  double family_wise_alpha = 0.01;
  int whiteness_lags = 20;
  LocalisationOptions localisation;
  int max_localised_failures = 5;
};

struct MonitorResult {
  Verdict verdict = Verdict::kGood;
  double gamma2 = 0.0;
  double eta2 = 0.0;
  int window_updates = 0;
  std::vector<ChannelFit> channels;
  std::vector<FaultInterval> faults;
  std::vector<Localisation> localisation;   // one per localised gradual failure, in time order
  std::vector<Localisation> discrepancies;  // forward/backward, most significant first
  double nis_mean = 0.0;
  double nis_band_low = 0.0;   // 1 − α/3 two-sided χ² band of the mean NIS
  double nis_band_high = 0.0;
  Eigen::MatrixXd window_ratio;  // K × 6 moving F (NaN until the first full window)
};

// What the raw samples show before any model: the spikes the screening
// repaired, and where the bench moved against its reference.
struct SampleScreening {
  std::vector<SampleOutlier> spikes;
  std::vector<BenchMotion> bench_motion;
};

MonitorResult Monitor(const ForwardPass& forward, const SmoothedPass& smoothed, const StateLayout& layout,
                      const SampleScreening& samples, const MonitorOptions& options);

// Appends [start, end] on `channel` to `faults`, merged into the channel's
// last interval of the kind when it starts within `join_gap_s` of its end.
void AddFaultInterval(std::vector<FaultInterval>& faults, std::string_view channel, double start_s, double end_s,
                      FaultKind kind, double statistic, double join_gap_s);
// The two-sided band of the mean NIS of `updates` scalar updates at the
// verdict's share of the family-wise level; without updates it is empty and
// excludes nothing.
struct MeanNisBand {
  double low = 0.0;
  double high = 0.0;
  bool Excludes(double nis_mean) const { return high > 0.0 && (nis_mean < low || nis_mean > high); }
};
MeanNisBand MeanNisBandOf(int updates, double family_wise_alpha);
// The verdict rule (above).
Verdict VerdictOf(bool gradual_failure, bool any_interval, bool nis_outside_band);
// In time order of their starts; intervals that start together keep their order.
void SortFaultIntervals(std::vector<FaultInterval>& faults);

const char* VerdictName(Verdict v);
const char* FaultKindName(FaultKind k);

}  // namespace insdiag::engine
