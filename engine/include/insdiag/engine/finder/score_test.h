// One-pass score (Lagrange-multiplier) test of every constant catalogue
// effect absent from the model, from the same forward pass.
//
// If the unit had an effect with parameters β that the model lacks, the
// filter's prediction error would carry a mean A_k β, where A propagates
// through the filter's own transitions and gains exactly as a bias-augmented
// filter's would (Friedland, "Treatment of bias in recursive filtering", IEEE
// Trans. AC 14(4), 1969):
//   between epochs  A ← Φ A + W,   W = Σ_samples (the candidate's regressor
//                                   mapped into the navigation errors: the
//                                   condensed interval's catalogue column, epoch_run.h)
//   per scalar update  X = h A,   A ← A − K X
// and the innovations would have mean X β. The Gaussian log-likelihood of the
// innovations as a function of β is then exactly quadratic:
//   ℓ(β) = ℓ(0) + sᵀβ − ½ βᵀ 𝓘 β,   s = Σ Xᵀ S⁻¹ ν,   𝓘 = Σ Xᵀ S⁻¹ X
// so the score statistic LM = sᵀ 𝓘⁻¹ s (Rao 1948; Silvey 1959) is χ²(rank 𝓘)
// without the effect and equals the likelihood ratio 2Δℓ of adding it; the
// one-step estimate β̂ = 𝓘⁻¹ s is its maximum-likelihood estimate with
// covariance 𝓘⁻¹.
//
// The quadratic is exact only while the filter's linearisation holds. Under
// the alternative the filter's attitude error is A_ψ β (the attitude rows of
// A), and the error model is first order in it (C̃ = (I − [ψ×]) C,
// model/state_layout.h), so the peak over the run of each column's attitude
// sensitivity is kept to say how far an estimate would move the filter.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "insdiag/engine/filter/forward_filter.h"
#include "insdiag/engine/model/effect_catalogue.h"

namespace insdiag::engine {

// One parameter of a candidate term (yaw harmonics have two).
using CandidateColumn = ConstantParameter;

// Every parameter of every constant catalogue term absent from `model`.
std::vector<CandidateColumn> AbsentConstantCandidates(const ErrorModel& model);

class ScoreTestObserver final : public FilterObserver {
 public:
  // `segment_epochs`: epochs per time segment of the per-channel, per-segment
  // breakdown of the score. `run` is the condensed run the pass filters.
  ScoreTestObserver(const StateLayout& layout, const EpochRun& run, std::vector<CandidateColumn> columns,
                    int segment_epochs);

  void OnPrediction(int index, const EpochInterval& epoch, const IntervalTransition& transition) override;
  void OnScalarUpdate(int channel, const ObservationRow& h, const Eigen::VectorXd& gain, double innovation,
                      double innovation_variance) override;

  const std::vector<CandidateColumn>& columns() const { return columns_; }
  const Eigen::VectorXd& score() const { return score_; }              // s
  const Eigen::MatrixXd& information() const { return information_; }  // 𝓘
  // s restricted to one channel and segment: score_by_segment()[channel](column, segment).
  const std::vector<Eigen::MatrixXd>& score_by_segment() const { return segment_score_; }
  int segment_epochs() const { return segment_epochs_; }
  // Per column: max over epochs of |A_ψ column| [rad per unit of the parameter].
  const Eigen::VectorXd& peak_attitude_sensitivity() const { return peak_attitude_sensitivity_; }

 private:
  const StateLayout& layout_;
  std::vector<CandidateColumn> columns_;
  int segment_epochs_;
  int epoch_ = -1;
  std::vector<int> run_columns_;  // each column's index among the condensed run's constant columns
  Eigen::MatrixXd sensitivity_;  // n × p, A
  Eigen::VectorXd score_;
  Eigen::MatrixXd information_;
  Eigen::VectorXd peak_attitude_sensitivity_;
  std::vector<Eigen::MatrixXd> segment_score_;  // per channel: p × segments
  Eigen::RowVectorXd X_;
};

}  // namespace insdiag::engine
