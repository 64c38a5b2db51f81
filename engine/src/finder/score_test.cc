#include "insdiag/engine/finder/score_test.h"

#include <cmath>

namespace insdiag::engine {

std::vector<CandidateColumn> AbsentConstantCandidates(const ErrorModel& model) {
  std::vector<CandidateColumn> out;
  for (const EffectTerm& term : AllCatalogueTerms()) {
    if (term.family->kind != EffectKind::kConstant || model.FindEffect(term) >= 0) continue;
    for (int p = 0; p < term.family->parameters_per_term; ++p) out.push_back({term, p});
  }
  return out;
}

ScoreTestObserver::ScoreTestObserver(const StateLayout& layout, std::vector<CandidateColumn> columns,
                                     int segment_epochs)
    : layout_(layout), columns_(std::move(columns)), segment_epochs_(std::max(1, segment_epochs)) {
  const auto p = static_cast<Eigen::Index>(columns_.size());
  W_y_.setZero(9, p);
  sensitivity_.setZero(layout.size(), p);
  score_.setZero(p);
  information_.setZero(p, p);
  segment_score_.assign(kChannelCount, Eigen::MatrixXd::Zero(p, 0));
  X_.setZero(p);
  for (size_t i = 0; i < columns_.size(); ++i) {
    const auto col = static_cast<Eigen::Index>(i);
    if (!terms_.empty() && terms_.back().term.Name() == columns_[i].term.Name()) {
      ++terms_.back().count;
    } else {
      terms_.push_back({columns_[i].term, col, 1});
      any_yaw_ = any_yaw_ || columns_[i].term.family->regressor == Regressor::kYawSinCos;
    }
  }
}

void ScoreTestObserver::OnSample(const NavigationDiscretisation&, const SampleCoupling& c) {
  // The candidate's sensor error over this sample, per unit of its parameter,
  // mapped into the interval-start coordinates: 9 multiply-adds a column.
  // One regressor evaluation per term (the yaw harmonics' sin ψ, cos ψ once
  // per sample for all axes): this loop runs for every sample of the run.
  double sin_yaw = 0.0, cos_yaw = 0.0;
  if (any_yaw_) {
    sin_yaw = std::sin(c.inputs.yaw_rad);
    cos_yaw = std::cos(c.inputs.yaw_rad);
  }
  for (const TermColumns& t : terms_) {
    if (t.term.family->regressor == Regressor::kYawSinCos) {
      regressor_[0] = sin_yaw;
      regressor_[1] = cos_yaw;
    } else {
      EvaluateRegressor(t.term, c.inputs, regressor_);
    }
    const auto column = c.Column(t.term.family->sensor, t.term.axis);
    for (int k = 0; k < t.count; ++k) W_y_.col(t.first + k).noalias() += column * regressor_[columns_[static_cast<size_t>(t.first + k)].parameter];
  }
}

void ScoreTestObserver::OnPrediction(const IntervalTransition& t) {
  // A ← Φ A + W, with W mapped from interval-start coordinates to the epoch.
  t.PropagateRows(sensitivity_);
  sensitivity_.topRows<9>().noalias() += t.A * W_y_;
  W_y_.setZero();
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
