// The seed's tests of the innovations, applied epoch after epoch (monitoring.h
// states them): β² = ν²/α² of each channel against its family-wise outlier
// threshold, and the moving-window F = Σν²/Σα² against its gradual-failure
// threshold. The monitor of a whole pass (Monitor) and the monitor of a test
// being recorded (live_monitor.h) both apply them through this class, so that
// one run's intervals are the same whichever way it was monitored.
//
// The family-wise thresholds depend on how many epochs are tested: the pass's
// own count afterwards, the planned test's while it runs.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "insdiag/engine/filter/observation.h"
#include "insdiag/engine/monitor/monitoring.h"

namespace insdiag::engine {

class InnovationTests {
 public:
  using PerChannel = std::array<double, kChannelCount>;

  // `planned_epochs`: the epochs the family-wise thresholds count;
  // `epoch_interval_s`: their spacing, which sets the window's length in
  // updates and how close two intervals must be to merge.
  InnovationTests(int planned_epochs, double epoch_interval_s, const MonitorOptions& options);

  // Tests the next epoch, whose update interval is (start_s, time_s], with
  // innovations ν and variances α². Where the reference does not hold (the
  // bench moved, monitor/bench_motion.h) the epoch is counted but not tested:
  // no outlier, and the windows over it test the rest.
  // Allocates only to record a new interval.
  void Add(double start_s, double time_s, const PerChannel& innovation, const PerChannel& innovation_variance,
           bool reference_holds = true);

  // Found so far, each channel's and kind's intervals in time order
  // (neighbouring ones merged); not sorted across channels.
  const std::vector<FaultInterval>& faults() const { return faults_; }
  // The last epoch's β² and window F (NaN until the first full window).
  const PerChannel& beta2() const { return beta2_; }
  const PerChannel& window_ratio() const { return window_ratio_; }
  bool gradual_found() const { return gradual_found_; }

  int epochs() const { return epochs_; }
  int window_updates() const { return window_; }
  double gamma2() const { return gamma2_; }
  double eta2() const { return eta2_; }
  double outlier_threshold() const { return outlier_threshold_; }
  double gradual_threshold() const { return gradual_threshold_; }
  // Per channel: epochs it was observed at, those with β² > γ², windows
  // tested (those holding an observation of it), windows with F > η².
  // A channel not observed at an epoch (ν = α² = 0) has β² NaN there.
  int observed(int channel) const { return observed_[static_cast<size_t>(channel)]; }
  int over_gamma2(int channel) const { return over_gamma2_[static_cast<size_t>(channel)]; }
  int windows(int channel) const { return windows_[static_cast<size_t>(channel)]; }
  int over_eta2(int channel) const { return over_eta2_[static_cast<size_t>(channel)]; }

 private:
  void AddInterval(int channel, double start_s, double end_s, FaultKind kind, double statistic);

  double epoch_interval_s_;
  int window_;
  double gamma2_, eta2_;
  double outlier_threshold_, gradual_threshold_, window_alpha_;
  int epochs_ = 0;
  // The last W epochs' ν² and α² per channel (a ring), and their sums.
  std::vector<PerChannel> window_nu2_, window_S_;
  std::vector<double> window_start_s_;
  PerChannel sum_nu2_{}, sum_S_{}, sum_S2_{};
  PerChannel beta2_{}, window_ratio_{};
  std::array<int, kChannelCount> observed_{}, window_observed_{}, windows_{}, over_gamma2_{}, over_eta2_{};
  std::vector<FaultInterval> faults_;
  bool gradual_found_ = false;
};

}  // namespace insdiag::engine
