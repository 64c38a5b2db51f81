#include "insdiag/engine/finder/score_test.h"

#include <cmath>

namespace insdiag::engine {

std::vector<CandidateColumn> AbsentConstantCandidates(const ErrorModel& model) {
  std::vector<CandidateColumn> out;
  for (const ConstantParameter& c : AllConstantParameters()) {
    if (model.FindEffect(c.term) < 0) out.push_back(c);
  }
  return out;
}

ScoreTestObserver::ScoreTestObserver(const StateLayout& layout, const EpochRun& run,
                                     std::vector<CandidateColumn> columns, int segment_epochs)
    : layout_(layout), columns_(std::move(columns)), segment_epochs_(std::max(1, segment_epochs)) {
  const auto p = static_cast<Eigen::Index>(columns_.size());
  sensitivity_.setZero(layout.size(), p);
  score_.setZero(p);
  information_.setZero(p, p);
  peak_attitude_sensitivity_.setZero(p);
  segment_score_.assign(kChannelCount, Eigen::MatrixXd::Zero(p, 0));
  X_.setZero(p);
  for (const CandidateColumn& c : columns_) run_columns_.push_back(run.ConstantColumn(c.term, c.parameter));
}

void ScoreTestObserver::OnPrediction(int, const EpochInterval& epoch, const IntervalTransition& t) {
  // A ← Φ A + W: the candidates' inputs over the interval, at the epoch.
  t.PropagateRows(sensitivity_);
  for (size_t i = 0; i < run_columns_.size(); ++i) {
    sensitivity_.col(static_cast<Eigen::Index>(i)).head<kNavigationStates>() +=
        epoch.constants.col(run_columns_[i]);
  }
  // After prediction, before the updates correct it: the largest the error gets.
  peak_attitude_sensitivity_ = peak_attitude_sensitivity_.cwiseMax(
      sensitivity_.middleRows<3>(layout_.attitude()).colwise().norm().transpose());
  ++epoch_;
  const int segment = epoch_ / segment_epochs_;
  if (segment >= segment_score_.front().cols()) {
    for (auto& m : segment_score_) m.conservativeResize(Eigen::NoChange, segment + 1), m.col(segment).setZero();
  }
}

void ScoreTestObserver::OnScalarUpdate(int channel, const ObservationRow& h, const Eigen::VectorXd& gain,
                                       double innovation, double S) {
  X_ = h.sign * sensitivity_.row(h.state);
  score_.noalias() += X_.transpose() * (innovation / S);
  information_.noalias() += X_.transpose() * (X_ / S);
  segment_score_[static_cast<size_t>(channel)].col(epoch_ / segment_epochs_).noalias() +=
      X_.transpose() * (innovation / S);
  sensitivity_.noalias() -= gain * X_;
}

}  // namespace insdiag::engine
