#include "insdiag/engine/monitor/live_step_scan.h"

#include <algorithm>
#include <cmath>

#include "insdiag/engine/filter/model_transitions.h"
#include "insdiag/engine/monitor/sample_screening.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine {

LiveStepScan::LiveStepScan(int state_size, int planned_epochs, double epoch_interval_s,
                           const LiveStepScanOptions& options)
    : window_(std::max(1, static_cast<int>(std::lround(options.window_s / epoch_interval_s)))),
      epoch_interval_s_(epoch_interval_s),
      min_onset_s_(options.min_onset_s) {
  const double tests = static_cast<double>(std::max(planned_epochs, 1)) * window_ * kSensorAxisCount;
  threshold_ = stats::ChiSquareQuantile(1.0 - options.family_wise_alpha / tests, 1.0);
  const int columns = window_ * kSensorAxisCount;
  A_ = Eigen::MatrixXd::Zero(state_size, columns);
  score_ = Eigen::VectorXd::Zero(columns);
  information_ = Eigen::VectorXd::Zero(columns);
  X_.resize(columns);
  onset_s_.assign(static_cast<size_t>(window_), 0.0);
}

void LiveStepScan::OnPrediction(const EpochInterval& epoch, const IntervalTransition& transition) {
  ++epoch_;
  if (epoch_ == 0) run_start_s_ = epoch.start_s;
  // The oldest onset leaves the window; this epoch's start enters it.
  const int slot = epoch_ % window_;
  A_.middleCols(slot * kSensorAxisCount, kSensorAxisCount).setZero();
  score_.segment(slot * kSensorAxisCount, kSensorAxisCount).setZero();
  information_.segment(slot * kSensorAxisCount, kSensorAxisCount).setZero();
  onset_s_[static_cast<size_t>(slot)] = epoch.start_s;
  transition.PropagateRows(A_);
  const int active = std::min(epoch_ + 1, window_);
  for (int back = 0; back < active; ++back) {
    const int s = (epoch_ - back) % window_;  // back ≤ epoch_: never negative
    for (int a = 0; a < kSensorAxisCount; ++a) {
      A_.col(s * kSensorAxisCount + a).head<kNavigationStates>() +=
          FaultColumn(epoch, a, Regressor::kStep, onset_s_[static_cast<size_t>(s)]);
    }
  }
}

void LiveStepScan::OnScalarUpdate(const ObservationRow& h, const Eigen::VectorXd& gain, double innovation,
                                  double innovation_variance) {
  X_.noalias() = h.sign * A_.row(h.state);
  score_.noalias() += (innovation / innovation_variance) * X_.transpose();
  information_.array() += X_.transpose().array().square() / innovation_variance;
  A_.noalias() -= gain * X_;
}

void LiveStepScan::CloseEpoch(double time_s) {
  largest_ = 0.0;
  int best = -1;
  const int active = std::min(epoch_ + 1, window_);
  for (int back = 0; back < active; ++back) {
    const int s = (epoch_ - back) % window_;  // back ≤ epoch_: never negative
    if (onset_s_[static_cast<size_t>(s)] - run_start_s_ < min_onset_s_) continue;
    for (int a = 0; a < kSensorAxisCount; ++a) {
      const int c = s * kSensorAxisCount + a;
      if (!(information_[c] > 0.0)) continue;
      const double T = score_[c] * score_[c] / information_[c];
      if (T > largest_) largest_ = T, best = c;
    }
  }
  if (best < 0 || largest_ <= threshold_) {
    detecting_ = false;
    return;
  }
  const std::string_view channel = kSensorChannelNames[best % kSensorAxisCount];
  const double onset_s = onset_s_[static_cast<size_t>(best / kSensorAxisCount)];
  // While a detection goes on, the evidence grows and may point to another
  // axis or onset than its first epoch did: the one step found is the best
  // explanation now (its peak the largest T seen).
  if (detecting_) {
    FaultInterval& current = steps_.back();
    if (largest_ >= current.peak_statistic) {
      current.channel = std::string(channel);
      current.start_s = onset_s;
    }
    current.end_s = time_s;
    current.peak_statistic = std::max(current.peak_statistic, largest_);
    return;
  }
  detecting_ = true;
  steps_.push_back({std::string(channel), onset_s, time_s, FaultKind::kAbrupt, largest_});
}

}  // namespace insdiag::engine
