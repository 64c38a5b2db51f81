#include "insdiag/engine/filter/smoother.h"

#include <cmath>
#include <limits>

#include <Eigen/Cholesky>

namespace insdiag::engine {
namespace {

// Relative size below which P_f − P_s counts as "the future adds nothing".
constexpr double kNoInformationRatio = 1e-9;

absl::Status CheckOptions(const ForwardPass& fw, const SmootherOptions& options) {
  const int n = fw.state_size;
  if (fw.epochs() == 0)
    return absl::InvalidArgumentError("smoother: the forward pass has no epochs");
  if (options.block_begin < 0 || options.block_size < 0 || options.block_begin + options.block_size > n) {
    return absl::InvalidArgumentError("smoother: the covariance block is outside the state");
  }
  for (int i : options.pair_states) {
    if (i < 0 || i + 1 >= n) return absl::InvalidArgumentError("smoother: a moment pair is outside the state");
  }
  return absl::OkStatus();
}

SmoothedPass SizedOutput(int epochs, int n, const SmootherOptions& options) {
  SmoothedPass out;
  out.x.resize(epochs, n);
  out.variance.resize(epochs, n);
  out.lag_one_covariance = Eigen::MatrixXd::Zero(epochs, n);
  out.backward_x.resize(epochs, n);
  out.backward_variance.resize(epochs, n);
  out.discrepancy.resize(epochs, n);
  if (options.block_size > 0) out.block_covariance.resize(epochs, PackedSize(options.block_size));
  out.pair_moments.assign(options.pair_states.size(),
                          Eigen::Matrix<double, Eigen::Dynamic, 7>::Zero(epochs, 7));
  return out;
}

// Epoch k's smoothed moments, and the backward (future-only) estimate that the
// forward and smoothed ones imply: x_b = x_f + (x_s − x_f) P_f / (P_f − P_s),
// per state (the two-filter form, Fraser & Potter, IEEE Trans. AC 14(4), 1969).
void RecordEpoch(int k, const ForwardPass& fw, const SmootherOptions& options,
                 const Eigen::VectorXd& xs, const Eigen::MatrixXd& Ps, const Eigen::MatrixXd& Pf,
                 SmoothedPass& out) {
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
  for (int i = 0; i < Ps.rows(); ++i) {
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
}

// The smoothed error's autocovariance R_e(j) of some states: from each
// reference epoch l (the later time), carry w = Cov(e_k, e_l[i]) backwards
// with w ← C_k w while l − k ≤ the largest lag, averaged over the references.
class ErrorAutocovariance {
 public:
  ErrorAutocovariance(int epochs, const SmootherOptions& options, SmoothedPass& out)
      : states_(options.error_acf_states),
        max_lag_(std::min(options.error_acf_max_lag, epochs - 1)),
        sums_(out.error_autocovariance) {
    sums_.assign(states_.size(),
                 std::vector<double>(static_cast<size_t>(std::max(max_lag_, 0) + 1), 0.0));
    if (!states_.empty() && max_lag_ >= 0) {
      const int count = std::max(1, std::min(options.error_acf_references, epochs - max_lag_));
      for (int r = 0; r < count; ++r) {
        references_.push_back(max_lag_ +
                              static_cast<int>((static_cast<long>(epochs - 1 - max_lag_) * r) /
                                               std::max(1, count - 1)));
      }
    }
    per_reference_ = references_.empty() ? 0.0 : 1.0 / static_cast<double>(references_.size());
  }

  // Starts the carriers of epoch l when it is a reference.
  void StartAt(int l, const Eigen::MatrixXd& Ps) {
    for (int ref : references_) {
      if (ref != l) continue;
      for (size_t slot = 0; slot < states_.size(); ++slot) {
        const int i = states_[slot];
        carriers_.push_back({l, slot, Ps.col(i)});
        sums_[slot][0] += Ps(i, i) * per_reference_;
      }
    }
  }

  // Steps every carrier from epoch k + 1 back to k: Cov(e_k, e_l[i]) = C_k Cov(e_{k+1}, e_l[i]).
  void CarryBackTo(int k, const Eigen::MatrixXd& gain_T) {
    for (auto it = carriers_.begin(); it != carriers_.end();) {
      it->w = gain_T.transpose() * it->w;
      const int epochs_apart = it->reference - k;
      const int i = states_[it->slot];
      sums_[it->slot][static_cast<size_t>(epochs_apart)] += it->w[i] * per_reference_;
      it = epochs_apart >= max_lag_ ? carriers_.erase(it) : std::next(it);
    }
  }

 private:
  struct Carrier {
    int reference;
    size_t slot;
    Eigen::VectorXd w;
  };
  const std::vector<int>& states_;
  const int max_lag_;
  std::vector<std::vector<double>>& sums_;
  std::vector<int> references_;
  std::vector<Carrier> carriers_;
  double per_reference_ = 0.0;
};

// The Rauch–Tung–Striebel gain's transpose, C_kᵀ = P_{k+1|k}⁻¹ Φ P_{k|k}
// (Rauch, Tung & Striebel, AIAA J. 3(8), 1965). The states span many orders
// of magnitude (metres, rad, rad/s): solve in Jacobi-scaled form so the
// Cholesky factor sees correlations, not units. Buffers are the caller's: the
// smoother runs in every EM step.
class SmootherGain {
 public:
  explicit SmootherGain(int n) : scale_(n), inv_scale_(n), P_scaled_(n, n), ldlt_(n) {}

  absl::Status Compute(const ForwardPass& fw, int k, const Eigen::MatrixXd& P_f,
                       const Eigen::MatrixXd& P_p, Eigen::MatrixXd& gain_T) {
    const int n = static_cast<int>(P_f.rows());
    gain_T = P_f;
    fw.transitions[static_cast<size_t>(k + 1)].PropagateRows(gain_T);
    for (int i = 0; i < n; ++i) {
      scale_[i] = std::sqrt(std::max(P_p(i, i), std::numeric_limits<double>::min()));
      inv_scale_[i] = 1.0 / scale_[i];
    }
    P_scaled_ = inv_scale_.asDiagonal() * P_p * inv_scale_.asDiagonal();
    ldlt_.compute(P_scaled_);
    if (ldlt_.info() != Eigen::Success) {
      return absl::InternalError("smoother: predicted covariance is not positive definite at epoch " +
                                 std::to_string(k + 1));
    }
    gain_T = inv_scale_.asDiagonal() * gain_T;
    ldlt_.solveInPlace(gain_T);
    gain_T = inv_scale_.asDiagonal() * gain_T;
    return absl::OkStatus();
  }

 private:
  Eigen::VectorXd scale_, inv_scale_;
  Eigen::MatrixXd P_scaled_;
  Eigen::LDLT<Eigen::MatrixXd> ldlt_;
};

}  // namespace

absl::StatusOr<SmoothedPass> RunSmoother(const ForwardPass& fw, const SmootherOptions& options) {
  if (absl::Status valid = CheckOptions(fw, options); !valid.ok()) return valid;
  const int n = fw.state_size;
  const int K = fw.epochs();
  SmoothedPass out = SizedOutput(K, n, options);

  Eigen::MatrixXd P_s, P_f, P_p, gain_T, diff;
  Eigen::VectorXd x_s = fw.x_filt.row(K - 1).transpose();
  UnpackSymmetric(fw.P_filt.row(K - 1).data(), n, P_s);
  UnpackSymmetric(fw.P_filt.row(K - 1).data(), n, P_f);
  RecordEpoch(K - 1, fw, options, x_s, P_s, P_f, out);
  ErrorAutocovariance error_acf(K, options, out);
  error_acf.StartAt(K - 1, P_s);

  // Per-epoch work in buffers sized once: the smoother runs in every EM step.
  SmootherGain smoother_gain(n);
  Eigen::MatrixXd spread(n, n);
  Eigen::VectorXd x_next(n), correction(n);
  for (int k = K - 2; k >= 0; --k) {
    UnpackSymmetric(fw.P_filt.row(k).data(), n, P_f);
    UnpackSymmetric(fw.P_pred.row(k + 1).data(), n, P_p);
    if (absl::Status gain = smoother_gain.Compute(fw, k, P_f, P_p, gain_T); !gain.ok()) return gain;

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
    RecordEpoch(k, fw, options, x_s, P_s, P_f, out);
    error_acf.CarryBackTo(k, gain_T);
    error_acf.StartAt(k, P_s);
  }
  return out;
}

}  // namespace insdiag::engine
