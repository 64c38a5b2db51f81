#include "insdiag/engine/filter/smoother.h"

#include <cmath>
#include <limits>

#include <Eigen/Cholesky>

namespace insdiag::engine {
namespace {

// Relative size below which P_f − P_s counts as "the future adds nothing".
constexpr double kNoInformationRatio = 1e-9;

}  // namespace

absl::StatusOr<SmoothedPass> RunSmoother(const ForwardPass& fw, const SmootherOptions& options) {
  const int n = fw.state_size;
  const int K = fw.epochs();
  if (K == 0) return absl::InvalidArgumentError("smoother: the forward pass has no epochs");
  if (options.block_begin < 0 || options.block_size < 0 || options.block_begin + options.block_size > n) {
    return absl::InvalidArgumentError("smoother: the covariance block is outside the state");
  }
  SmoothedPass out;
  out.x.resize(K, n);
  out.variance.resize(K, n);
  out.lag_one_covariance = Eigen::MatrixXd::Zero(K, n);
  out.backward_x.resize(K, n);
  out.backward_variance.resize(K, n);
  out.discrepancy.resize(K, n);
  if (options.block_size > 0) out.block_covariance.resize(K, PackedSize(options.block_size));
  for (int i : options.pair_states) {
    if (i < 0 || i + 1 >= n) return absl::InvalidArgumentError("smoother: a moment pair is outside the state");
  }
  out.pair_moments.assign(options.pair_states.size(), Eigen::Matrix<double, Eigen::Dynamic, 7>::Zero(K, 7));

  Eigen::MatrixXd P_s, P_f, P_p, gain_T, diff;
  Eigen::VectorXd x_s = fw.x_filt.row(K - 1).transpose();
  UnpackSymmetric(fw.P_filt.row(K - 1).data(), n, P_s);
  Eigen::VectorXd scale(n), inv_scale(n);

  auto record = [&](int k, const Eigen::VectorXd& xs, const Eigen::MatrixXd& Ps, const Eigen::MatrixXd& Pf) {
    out.x.row(k) = xs.transpose();
    out.variance.row(k) = Ps.diagonal().transpose();
    if (options.block_size > 0) {
      const Eigen::MatrixXd block =
          Ps.block(options.block_begin, options.block_begin, options.block_size, options.block_size);
      PackSymmetric(block, out.block_covariance.row(k).data());
    }
    for (size_t p = 0; p < options.pair_states.size(); ++p) {
      const int i = options.pair_states[p];
      out.pair_moments[p].block<1, 3>(k, 0) << Ps(i, i), Ps(i, i + 1), Ps(i + 1, i + 1);
    }
    for (int i = 0; i < n; ++i) {
      const double pf = Pf(i, i);
      const double ps = Ps(i, i);
      const double gain = pf - ps;
      const double xf = fw.x_filt(k, i);
      if (gain > kNoInformationRatio * pf && gain > 0.0) {
        const double dx = xs[i] - xf;
        out.discrepancy(k, i) = dx * dx / gain;
        out.backward_x(k, i) = xf + dx * pf / gain;
        out.backward_variance(k, i) = pf * ps / gain;
      } else {
        out.discrepancy(k, i) = 0.0;
        out.backward_x(k, i) = std::numeric_limits<double>::quiet_NaN();
        out.backward_variance(k, i) = std::numeric_limits<double>::infinity();
      }
    }
  };
  UnpackSymmetric(fw.P_filt.row(K - 1).data(), n, P_f);
  record(K - 1, x_s, P_s, P_f);

  // Error autocovariance: from each reference epoch l (the later time), carry
  // w = Cov(e_k, e_l[i]) backwards with w ← C_k w while l − k ≤ max lag.
  const int max_lag = std::min(options.error_acf_max_lag, K - 1);
  const auto n_acf = options.error_acf_states.size();
  out.error_autocovariance.assign(n_acf, std::vector<double>(static_cast<size_t>(std::max(max_lag, 0) + 1), 0.0));
  std::vector<int> references;
  if (n_acf > 0 && max_lag >= 0) {
    const int count = std::max(1, std::min(options.error_acf_references, K - max_lag));
    for (int r = 0; r < count; ++r) {
      references.push_back(max_lag + static_cast<int>((static_cast<long>(K - 1 - max_lag) * r) / std::max(1, count - 1)));
    }
  }
  // Active carriers: (reference epoch, state slot, vector).
  struct Carrier {
    int reference;
    size_t slot;
    Eigen::VectorXd w;
  };
  std::vector<Carrier> carriers;
  const double per_reference = references.empty() ? 0.0 : 1.0 / static_cast<double>(references.size());
  auto start_carriers = [&](int l, const Eigen::MatrixXd& Ps) {
    for (int ref : references) {
      if (ref != l) continue;
      for (size_t slot = 0; slot < n_acf; ++slot) {
        const int i = options.error_acf_states[slot];
        carriers.push_back({l, slot, Ps.col(i)});
        out.error_autocovariance[slot][0] += Ps(i, i) * per_reference;
      }
    }
  };
  start_carriers(K - 1, P_s);

  // Per-epoch work in buffers sized once: the smoother runs in every EM step.
  Eigen::MatrixXd P_scaled(n, n), spread(n, n);
  Eigen::LDLT<Eigen::MatrixXd> ldlt(n);
  Eigen::VectorXd x_next(n), correction(n);
  for (int k = K - 2; k >= 0; --k) {
    UnpackSymmetric(fw.P_filt.row(k).data(), n, P_f);
    UnpackSymmetric(fw.P_pred.row(k + 1).data(), n, P_p);
    // C_kᵀ = P_{k+1|k}⁻¹ Φ P_{k|k}. The states span many orders of magnitude
    // (metres, rad, rad/s): solve in Jacobi-scaled form so the Cholesky factor
    // sees correlations, not units.
    gain_T = P_f;
    fw.transitions[static_cast<size_t>(k + 1)].PropagateRows(gain_T);
    for (int i = 0; i < n; ++i) {
      scale[i] = std::sqrt(std::max(P_p(i, i), std::numeric_limits<double>::min()));
      inv_scale[i] = 1.0 / scale[i];
    }
    P_scaled = inv_scale.asDiagonal() * P_p * inv_scale.asDiagonal();
    ldlt.compute(P_scaled);
    if (ldlt.info() != Eigen::Success) {
      return absl::InternalError("smoother: predicted covariance is not positive definite at epoch " +
                                 std::to_string(k + 1));
    }
    gain_T = inv_scale.asDiagonal() * gain_T;
    ldlt.solveInPlace(gain_T);
    gain_T = inv_scale.asDiagonal() * gain_T;

    x_next = x_s - fw.x_pred.row(k + 1).transpose();
    correction.noalias() = gain_T.transpose() * x_next;
    x_s = fw.x_filt.row(k).transpose() + correction;
    // P_{k+1,k|K} = P_{k+1|K} C_kᵀ: its diagonal, and a pair's 2 × 2, from
    // the columns needed (P_{k+1|K} is symmetric), not the whole product.
    out.lag_one_covariance.row(k) = P_s.cwiseProduct(gain_T).colwise().sum();
    for (size_t p = 0; p < options.pair_states.size(); ++p) {
      const int i = options.pair_states[p];
      out.pair_moments[p].block<1, 4>(k, 3) << out.lag_one_covariance(k, i), P_s.col(i).dot(gain_T.col(i + 1)),
          P_s.col(i + 1).dot(gain_T.col(i)), out.lag_one_covariance(k, i + 1);
    }
    // P_{k|K} = P_{k|k} + C_k (P_{k+1|K} − P_{k+1|k}) C_kᵀ, its lower half
    // computed (it is symmetric) and mirrored.
    diff = P_s - P_p;
    spread.noalias() = diff * gain_T;
    P_s = P_f;
    P_s.triangularView<Eigen::Lower>() += gain_T.transpose() * spread;
    for (int j = 1; j < n; ++j) {
      for (int i = 0; i < j; ++i) P_s(i, j) = P_s(j, i);
    }
    record(k, x_s, P_s, P_f);
    for (auto it = carriers.begin(); it != carriers.end();) {
      it->w = gain_T.transpose() * it->w;  // Cov(e_k, e_l[i]) = C_k Cov(e_{k+1}, e_l[i])
      const int epochs_apart = it->reference - k;
      const int i = options.error_acf_states[it->slot];
      out.error_autocovariance[it->slot][static_cast<size_t>(epochs_apart)] += it->w[i] * per_reference;
      it = epochs_apart >= max_lag ? carriers.erase(it) : std::next(it);
    }
    start_carriers(k, P_s);
  }
  return out;
}

}  // namespace insdiag::engine
