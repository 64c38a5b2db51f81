// A bias that settles after power-up (catalogue family warm_up): the score
// test of b·e^{−(t − t_s)/τ} on every sensor axis, over a grid of time
// constants τ, from one forward pass of a model that lacks it.
//
// With τ fixed the warm-up is a constant b whose regressor decays, so the
// score test of score_test.h holds as it is: the filter, which does not
// know of it, turns it into an innovation mean X_k b, with
//   between epochs  A ← Φ A + W_k(τ),   per scalar update  X = h A,  A ← A − K X
//   s(τ) = Σ Xᵀ S⁻¹ ν,  𝓘(τ) = Σ Xᵀ S⁻¹ X,  T(τ) = s²/𝓘 = 2Δℓ,  b̂ = s/𝓘,  SE 𝓘^{−1/2}
// (Friedland 1969; Rao 1948). Over interval k, whose samples j start s_j
// after its start t_k, the column is Σ_j b_j e^{−(t_k + s_j + Δt/2 − t_s)/τ},
// b_j the sample's coupling (epoch_run.h); to second order in s_j/τ
//   W_k(τ) = e^{−(t_k + Δt/2 − t_s)/τ} (μ_0 − μ_1/τ + μ_2/(2τ²))
// of the axis' coupling moments μ_p, with a relative error below
// (Δ_k/τ)³/6 for an interval of Δ_k (1e-6 at one second and τ = 5 s).
//
// The warm-up settles to a steady value c that the run's mean, or a drift
// started at zero, does not hold: the test is of b beside c (the axis'
// turn-on bias column, epoch_run.h), the partial score and information
//   s_b|c = s_b − 𝓘_bc 𝓘_cc⁻¹ s_c,   𝓘_b|c = 𝓘_bb − 𝓘_bc² / 𝓘_cc
// (a constant alone is no warm-up), unless the model carries c already.
// The maximum of T over the τ tried is not χ²(1): as for an onset
// (onset_scan.h) its p-value is Davies' bound with the path length V =
// Σ_g arccos ρ(τ_g, τ_{g+1}) the standardised score traces over the grid,
// ρ the correlation of successive scores, 𝓘_{g,g+1}/√(𝓘_g 𝓘_{g+1})
// (Davies, Biometrika 74(1), 1987). τ̂ is placed at the vertex of the
// parabola through T at the best grid point and its neighbours, in ln τ.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "insdiag/engine/filter/epoch_run.h"
#include "insdiag/engine/filter/forward_filter.h"
#include "insdiag/engine/finder/onset_scan.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/model/state_layout.h"
#include "insdiag/engine/monitor/bench_motion.h"
#include "insdiag/engine/report.h"

namespace insdiag::engine {

// The time constants tried: log-spaced by `ratio` from the span at the
// run's start that the fault scan leaves to the start itself
// (OnsetScanOptions::min_side_s: a change within it is the turn-on bias, and
// a transient that settles within it is the start's too; the monitor does
// not hold a bench that moves there against the unit) to the run's length.
struct WarmUpGrid {
  double shortest_s = OnsetScanOptions{}.min_side_s;
  double longest_share_of_run = 1.0;
  double ratio = 1.7782794100389228;  // 10^{1/4}
};
std::vector<double> WarmUpTimeConstants(const EpochRun& run, const WarmUpGrid& grid);

// The best time constant of one axis' warm-up.
struct WarmUpFit {
  EffectTerm term;             // gyro_warm_up.x, acc_warm_up.z, …
  bool identifiable = false;   // false: the run carries no information on it
  double time_constant_s = 0.0;
  double statistic = 0.0;      // max over τ of T = 2Δℓ
  double p_value = 1.0;        // Davies' bound over the τ tried
  double estimate = 0.0;       // b̂ at τ̂, the start value [rad/s | m/s²]
  double std_error = 0.0;
  double path_length = 0.0;    // V
  int time_constants_tried = 0;
};

// The score sums of every axis' warm-up at every τ, gathered in a forward
// pass of the model laid out by `layout` (columns: axis-major, τ within;
// then each axis' steady value).
//
// The updates of intervals in which the bench moved (monitor/bench_motion.h)
// are no evidence: they test the bench, not the unit, as the monitor holds.
class WarmUpScoreObserver final : public FilterObserver {
 public:
  WarmUpScoreObserver(const StateLayout& layout, const EpochRun& run, std::vector<double> time_constants_s,
                      const std::vector<BenchMotion>* bench_motion = nullptr);

  void OnPrediction(int index, const EpochInterval& epoch, const IntervalTransition& transition) override;
  void OnScalarUpdate(int channel, const ObservationRow& h, const Eigen::VectorXd& gain, double innovation,
                      double innovation_variance) override;

  // The fit of each of the six sensor axes' warm-up whose term is not in `model`.
  std::vector<WarmUpFit> Fits(const ErrorModel& model) const;

 private:
  std::vector<double> time_constants_s_;
  const std::vector<BenchMotion>* bench_motion_ = nullptr;
  bool bench_moved_ = false;  // over the interval being updated
  std::vector<int> steady_columns_;  // per sensor axis, its turn-on bias among the run's constant columns
  double start_s_ = 0.0;
  Eigen::MatrixXd sensitivity_;  // n × columns, A
  Eigen::VectorXd score_;
  Eigen::MatrixXd information_;
  Eigen::RowVectorXd X_;
};

// The fits as missing-effect candidates (source "SCORE"), with their
// statistic, estimate and time constant, two parameters (the start value and
// τ) for the criteria (`scalar_updates` is the N of BIC), but not tested:
// the bound over τ is not calibrated on drifts identified from the same run.
std::vector<EffectCandidate> WarmUpCandidates(const std::vector<WarmUpFit>& fits, int scalar_updates);

// Every sensor axis' warm-up term the model lacks, scanned over the grid's
// time constants by one forward pass of `model` over `run`.
absl::StatusOr<std::vector<WarmUpFit>> ScanWarmUps(const EpochRun& run, const ErrorModel& model,
                                                   const WarmUpGrid& grid,
                                                   const std::vector<BenchMotion>* bench_motion = nullptr);

}  // namespace insdiag::engine
