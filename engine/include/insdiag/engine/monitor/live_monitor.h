// Monitoring of a test while it is being recorded (docs/LIVE.md).
//
// The samples are condensed as they arrive (filter/epoch_run.h,
// RunCondenser) with the a-priori model as the pilot, whose filter is that
// model's forward pass; each epoch's innovations go through the seed's tests
// (monitor/innovation_tests.h) as soon as the epoch closes. The family-wise
// thresholds count the planned test's epochs, so the intervals found live
// are the ones Monitor finds in the same model's forward pass of the
// completed run when the run lasted as planned. Beside them, bias steps are
// scanned for as they happen (monitor/live_step_scan.h): ABRUPT intervals,
// which the analysis of the stored run reports from its own whole-run scan.
//
// An epoch closes when the two samples after it have arrived (the table's
// motion within a sample is reconstructed from the reference attitudes on
// both sides, nav/table_motion.h): an interval is shown one update interval
// and two samples after it starts.
//
// Not live: the spike screening of the raw samples and the forward/backward
// discrepancies, which need the whole run (the analysis of the stored run
// has them).
#pragma once

#include <absl/status/statusor.h>

#include <array>
#include <memory>
#include <optional>
#include <vector>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/filter/epoch_run.h"
#include "insdiag/engine/filter/forward_filter.h"
#include "insdiag/engine/model/error_model.h"
#include "insdiag/engine/monitor/innovation_tests.h"
#include "insdiag/engine/monitor/live_step_scan.h"
#include "insdiag/engine/monitor/monitoring.h"

namespace insdiag::engine {

struct LiveMonitorOptions {
  MonitorOptions monitor;
  LiveStepScanOptions steps;
  double update_interval_s = FilterOptions{}.update_interval_s;
  // The test's planned length: the family-wise thresholds count its epochs.
  double planned_duration_s = 3600.0;
  // The nominal Δt is the median of the first intervals, this many.
  int nominal_interval_samples = 11;

  absl::Status Validate() const;
};

// What the monitor has seen so far.
struct LiveStatus {
  std::size_t samples = 0;  // arrived
  int epochs = 0;           // tested
  double time_s = 0.0;      // the last tested epoch (the run's t)
  InnovationTests::PerChannel beta2{};         // the last epoch's β² per channel
  InnovationTests::PerChannel window_ratio{};  // the last window's F (NaN until a window is full)
  std::vector<FaultInterval> faults;           // in time order
  double nis_mean = 0.0;
  double nis_band_low = 0.0, nis_band_high = 0.0;
  double gamma2 = 0.0, eta2 = 0.0;
  double outlier_threshold = 0.0, gradual_threshold = 0.0;  // family-wise, on β² and F
  double step_statistic = 0.0, step_threshold = 0.0;         // the step scan's largest T now, and its threshold
  int planned_epochs = 0;
  Verdict verdict = Verdict::kGood;
};

class LiveMonitor final : private FilterObserver {
 public:
  // `run` holds the test's metadata and outlives the monitor; samples are
  // appended to it as they arrive. `model`: the a-priori model (analysis.h,
  // APrioriModel).
  static absl::StatusOr<std::unique_ptr<LiveMonitor>> Create(const BenchRun& run, const ErrorModel& model,
                                                             const LiveMonitorOptions& options);

  // Tests the epochs the samples appended since the last call complete;
  // returns how many.
  absl::StatusOr<int> Advance();
  // The test has ended: tests the rest (the last epoch may be short).
  absl::StatusOr<int> Finish();

  LiveStatus Status() const;

 private:
  LiveMonitor(const BenchRun& run, const ErrorModel& model, const LiveMonitorOptions& options);
  absl::Status StartCondensing();

  void OnPrediction(int index, const EpochInterval& epoch, const IntervalTransition& transition) override;
  void OnScalarUpdate(int channel, const ObservationRow& h, const Eigen::VectorXd& gain, double innovation,
                      double innovation_variance) override;
  void OnEpochUpdated(int index, const EpochInterval& epoch) override;

  const BenchRun& run_;
  const ErrorModel model_;
  const LiveMonitorOptions options_;
  std::unique_ptr<RunCondenser> condenser_;
  std::optional<InnovationTests> tests_;
  std::optional<LiveStepScan> steps_;
  int planned_epochs_ = 0;
  double epoch_start_s_ = 0.0, epoch_time_s_ = 0.0;
  InnovationTests::PerChannel innovation_{}, innovation_variance_{};
  double nis_sum_ = 0.0;
  int updates_ = 0;
};

}  // namespace insdiag::engine
