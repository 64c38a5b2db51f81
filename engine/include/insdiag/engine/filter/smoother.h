// Backward processing: the fixed-interval smoother over a forward pass, the
// backward (future-data) estimates, and the seed's forward/backward
// discrepancy per state.
//
// Rauch–Tung–Striebel form (Rauch, Tung & Striebel, AIAA J. 3(8), 1965),
// over the epochs of the forward pass, with Φ_{k+1} the stored interval map:
//   C_k   = P_{k|k} Φ_{k+1}ᵀ P_{k+1|k}⁻¹
//   x_{k|K} = x_{k|k} + C_k (x_{k+1|K} − x_{k+1|k})
//   P_{k|K} = P_{k|k} + C_k (P_{k+1|K} − P_{k+1|k}) C_kᵀ
//   P_{k+1,k|K} = P_{k+1|K} C_kᵀ            (lag-one covariance)
// The feedback resets of the forward pass are known inputs and cancel in
// x_{k+1|K} − x_{k+1|k}.
//
// Backward estimates. The smoothed estimate combines the forward estimate
// (data 1…k) with the information of the future data k+1…K alone
// (Fraser & Potter, IEEE Trans. AC 14(4), 1969): P_s⁻¹ = P_f⁻¹ + P_b⁻¹.
// Per state i, the marginal backward estimate and variance follow as
//   x_b = x_f + (x_s − x_f) P_f/(P_f − P_s),   P_b = P_f P_s/(P_f − P_s).
// Discrepancy: d_i = (x_s,i − x_f,i)² / (P_f,ii − P_s,ii), distributed as
// χ²(1) when the model holds (the correction the future data make to the
// forward estimate, against its predicted variance). For a scalar state it
// equals (x_f − x_b)²/(P_f + P_b): the seed's comparison of estimates
// obtained in forward and backward time, which localises a trouble to a
// sensor.
#pragma once

#include <absl/status/statusor.h>

#include <vector>

#include <Eigen/Core>

#include "insdiag/engine/filter/forward_filter.h"

namespace insdiag::engine {

// The smoother's error autocovariance of a state, for correlation processing:
//   R_e(j) = mean over reference epochs l of Cov(e_{l−j}, e_l | all data),  e = x − x_{·|K}
//   Cov(e_{l−j}, e_l) = C_{l−j} ⋯ C_{l−1} P_{l|K}[:, i]   (the RTS gains, taken backwards)
// so that the autocovariance of the smoothed estimates, R_x̂ = R_x − R_e (the
// smoothed estimate is orthogonal to its error), can be corrected to the process's.
struct SmoothedPass {
  Eigen::MatrixXd x;         // K × n smoothed estimates x_{k|K}
  Eigen::MatrixXd variance;  // K × n diagonal of P_{k|K}
  // K × n: Cov(x_{k+1}, x_k | all data), diagonal, (row K−1 is zero).
  Eigen::MatrixXd lag_one_covariance;
  Eigen::MatrixXd backward_x;         // K × n marginal backward estimates (NaN where the future says nothing)
  Eigen::MatrixXd backward_variance;  // K × n
  Eigen::MatrixXd discrepancy;        // K × n d_i (0 where the future says nothing)
  // Full smoothed covariance of the requested block of states, K rows of
  // PackedSize(block size) (empty when no block was requested).
  PackedCovariances block_covariance;
  // R_e(j), j = 0 … max lag, per requested state (SmootherOptions::error_acf_states).
  std::vector<std::vector<double>> error_autocovariance;
  // Per requested pair of states (i, i+1) (SmootherOptions::pair_states), K
  // rows of the pair's smoothed covariance and lag-one covariance:
  //   [P₀₀ P₀₁ P₁₁ | L₀₀ L₀₁ L₁₀ L₁₁],  P = Cov(x_k | all data),
  //   L_ij = Cov(x_{k+1,i}, x_{k,j} | all data)  (row K−1: L = 0)
  // — the second moments the M-step of a second-order Markov pair needs.
  std::vector<Eigen::Matrix<double, Eigen::Dynamic, 7>> pair_moments;
};

struct SmootherOptions {
  // States whose joint smoothed covariance to keep (e.g. the base drifts for NEES).
  int block_begin = 0;
  int block_size = 0;
  // States whose smoother-error autocovariance to compute, up to this lag in
  // epochs, averaged over this many reference epochs spread over the run.
  std::vector<int> error_acf_states;
  int error_acf_max_lag = 0;
  int error_acf_references = 32;
  // First states of the pairs whose 2×2 moments to keep (SmoothedPass::pair_moments).
  std::vector<int> pair_states;
};

absl::StatusOr<SmoothedPass> RunSmoother(const ForwardPass& forward, const SmootherOptions& options = {});

}  // namespace insdiag::engine
