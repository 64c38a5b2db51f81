// A model's interval transitions over a condensed run (epoch_run.h): the Φ
// and Q of each update interval, built from the interval's coupling moments
// and the model's sensor states without touching the samples.
//
// Per sensor state (error_model.h, state_layout.h):
//   constant effect      B column = the interval's catalogue column K[:, i]
//   fault effect         B column = 0 before the onset; after it, the step's
//                        μ_0 or the ramp's μ_1 + (t_start + Δt/2 − t₀) μ_0 of
//                        its sensor axis (the sample means of 1 and t − t₀);
//                        in the interval the onset falls in, the samples
//                        after it (FaultColumn)
//   drift, walk, pair    B, Q_ns, Q_nn from the coupling's quadratic
//                        reconstruction, the state's per-sample transition
//                        d and noise q (epoch_run.h, header), and the
//                        sample's mean of the state (GridWeights)
//   D, Q_ss              the exact discretisation over the interval's length
//                        (SensorBlocks::Discretise): M samples of a linear
//                        process are one step of M Δt
// and Q_nn also takes the white noise and quantisation of every sensor axis,
// N_a² W_a + Q_a² Q_a (exact).
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

#include "insdiag/engine/filter/epoch_run.h"
#include "insdiag/engine/model/error_dynamics.h"
#include "insdiag/engine/model/error_model.h"
#include "insdiag/engine/model/state_layout.h"

namespace insdiag::engine {

// Sums over an interval's sample grid for one sensor state's block (one state,
// or a second-order pair whose first state reaches the output), already
// multiplied by the inverse moment Gram S⁻¹ (epoch_run.h):
//   B = Σ_q μ_q w_q,   Q_ns = Σ_q μ_q v_q,   Q_nn += Σ_k ν_k ν_kᵀ, ν_k = Σ_q μ_q L_qk
// with the per-sample noise q folded into v and L (U = L Lᵀ).
struct StateGridWeights {
  Eigen::Matrix<double, kCouplingMoments, 2> w = Eigen::Matrix<double, kCouplingMoments, 2>::Zero();
  Eigen::Matrix<double, kCouplingMoments, 2> v = Eigen::Matrix<double, kCouplingMoments, 2>::Zero();
  Eigen::Matrix<double, kCouplingMoments, kCouplingMoments> L =
      Eigen::Matrix<double, kCouplingMoments, kCouplingMoments>::Zero();
};

// The weights for M samples of Δt with per-sample transition `d` (its
// top-left `size` × `size` block), per-sample noise q·I and what each sample
// carries of the block, its mean over the sample (`mean`,
// SensorBlocks::SampleMeans), given the interval's moment Gram `gram` (only
// the moments up to degree min(2, M − 1) are used: with fewer samples the
// quadratic is not determined). A drift's mean over a sample varies less
// from sample to sample than its value at the sample's start: where a
// sample is long beside the drift's noise (1 Hz, a 1 mg drift of τ 300 s)
// the difference is a tenth of the innovations' variance.
StateGridWeights GridWeights(const Eigen::Matrix2d& d, int size, double q,
                             const SensorBlocks::SampleMean& mean, int samples, double dt,
                             const Eigen::Matrix<double, kCouplingMoments, kCouplingMoments>& gram);

// A fault effect's column over interval `e` for a unit value of its
// parameter on `sensor_axis` (SensorAxisIndex): zero before `onset_s`, the
// whole interval's after it, and for the interval the onset falls in, the
// share of its samples after the onset (the coupling's quadratic summed
// against them).
NavigationVector FaultColumn(const EpochInterval& e, int sensor_axis, Regressor fault,
                             double onset_s);

class ModelTransitions {
 public:
  // `model`, `layout` and `run` must outlive this object.
  ModelTransitions(const ErrorModel& model, const StateLayout& layout, const EpochRun& run);

  // The transition and noise over `epoch`'s interval (valid until the next call).
  const IntervalTransition& Build(const EpochInterval& epoch);

 private:
  struct StateSource {
    int state = 0;            // among the sensor states
    int block = 0;            // index into SensorBlocks::blocks
    int size = 1;             // 2 for a second-order pair
    int axis = 0;             // sensor axis (SensorAxisIndex)
    int constant_column = -1; // ≥ 0: a constant effect's catalogue column
    Regressor fault = Regressor::kNone;  // kStep or kRamp for a fault effect
    double onset_s = 0.0;
  };
  void PrepareGrid(int samples, double dt, const Eigen::Matrix<double, kCouplingMoments, kCouplingMoments>& gram,
                   double interval_s);

  const ErrorModel& model_;
  const StateLayout& layout_;
  const EpochRun& run_;
  std::vector<StateSource> sources_;
  // The grid the weights and the sensor blocks were prepared for.
  int grid_samples_ = -1;
  double grid_dt_ = 0.0;
  Eigen::Matrix<double, kCouplingMoments, kCouplingMoments> grid_gram_ =
      Eigen::Matrix<double, kCouplingMoments, kCouplingMoments>::Zero();
  std::vector<StateGridWeights> weights_;  // per source (unused for constants)
  SensorBlocks D_, Qs_;
  Eigen::Matrix<double, kSensorAxisCount, 1> white_var_;  // N² per sensor axis
  Eigen::Vector3d quantisation_var_;                      // Q² per accelerometer axis
  Matrix9d initial_navigation_covariance_;                // of a segment's start (forward_filter.h)
  IntervalTransition t_;
};

}  // namespace insdiag::engine
