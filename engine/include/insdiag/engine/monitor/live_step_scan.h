// Bias steps found while the test runs: the generalised likelihood ratio of
// a step on each sensor axis at each onset within the last `window_s`,
// carried forward epoch by epoch through the filter's own transitions and
// gains (Willsky & Jones, IEEE Trans. AC 21(1), 1976, the windowed GLR; the
// whole run's backward form is finder/onset_scan.h, whose notation this
// follows). For a step β on sensor axis a from the start of epoch θ:
//
//   A_k = Φ_k A_{k−1} + W_k          (W_k = FaultColumn: the interval's μ_0 of axis a)
//   per scalar update c:  X = h_c A,  s += X ν_c / S_c,  I += X² / S_c,  A ← A − K_c X
//   T(θ, a) = s² / I                  (2Δℓ at β̂ = s / I, SE 1/√I)
//
// After each epoch the largest T over the window's onsets and the six axes
// is tested against a family-wise threshold: Bonferroni over every (epoch,
// onset, axis) of the planned test, the χ²(1) quantile at α / (K L 6). The
// onsets are strongly correlated, so the level is conservative; the
// false-alarm rate measured on healthy runs is in docs/LIVE.md.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "insdiag/engine/filter/epoch_run.h"
#include "insdiag/engine/filter/observation.h"
#include "insdiag/engine/model/error_dynamics.h"
#include "insdiag/engine/monitor/monitoring.h"

namespace insdiag::engine {

struct LiveStepScanOptions {
  double window_s = 120.0;          // onsets this far back are tried
  double min_onset_s = 60.0;        // after the run's start: earlier, a jump is the turn-on bias
  double family_wise_alpha = 0.01;  // over the planned test
};

class LiveStepScan {
 public:
  // `state_size`: the filter's; `planned_epochs` and `epoch_interval_s` as
  // for InnovationTests.
  LiveStepScan(int state_size, int planned_epochs, double epoch_interval_s, const LiveStepScanOptions& options);

  // The filter's hooks (forward_filter.h, FilterObserver), in its order.
  void OnPrediction(const EpochInterval& epoch, const IntervalTransition& transition);
  void OnScalarUpdate(const ObservationRow& h, const Eigen::VectorXd& gain, double innovation,
                      double innovation_variance);
  // After the epoch's updates: tests the window, records a step found.
  void CloseEpoch(double time_s);

  // Steps found so far: ABRUPT intervals on the sensor channel ("gyro_x" …)
  // from the onset to the last epoch that still shows it. One interval per
  // run of epochs over the threshold, named by the (onset, axis) of the
  // largest T in it: what a step is attributed to may change while the
  // evidence grows.
  const std::vector<FaultInterval>& steps() const { return steps_; }
  double threshold() const { return threshold_; }
  double largest_statistic() const { return largest_; }  // this epoch's max T

 private:
  int window_;  // onsets (epochs) in the window
  double epoch_interval_s_;
  double min_onset_s_;
  double threshold_;
  int epoch_ = -1;
  double run_start_s_ = 0.0;
  Eigen::MatrixXd A_;  // n × (window · 6): column slot·6 + axis
  Eigen::VectorXd score_, information_;
  Eigen::RowVectorXd X_;
  std::vector<double> onset_s_;  // per slot
  double largest_ = 0.0;
  bool detecting_ = false;  // the last epoch was over the threshold
  std::vector<FaultInterval> steps_;
};

}  // namespace insdiag::engine
