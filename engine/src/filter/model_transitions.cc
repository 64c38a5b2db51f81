#include "insdiag/engine/filter/model_transitions.h"

#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "insdiag/engine/filter/forward_filter.h"

namespace insdiag::engine {
namespace {

using GramMatrix = Eigen::Matrix<double, kCouplingMoments, kCouplingMoments>;

// Relative change of an epoch's sample interval or Gram matrix below which
// the last grid weights still serve: rounding of the sample times, not a
// different sampling.
constexpr double kGridRelativeTolerance = 1e-12;

// S⁻¹ of the leading (degree + 1) block of the Gram, zero elsewhere.
GramMatrix InverseGram(const GramMatrix& gram, int degree) {
  GramMatrix inverse = GramMatrix::Zero();
  const int n = degree + 1;
  // The moments span seconds⁰ to seconds⁴: scale so the solve sees a
  // well-conditioned matrix.
  Eigen::VectorXd scale(n);
  for (int i = 0; i < n; ++i) scale[i] = 1.0 / std::sqrt(std::max(gram(i, i), 1e-300));
  const Eigen::MatrixXd scaled = scale.asDiagonal() * gram.topLeftCorner(n, n) * scale.asDiagonal();
  inverse.topLeftCorner(n, n) = scale.asDiagonal() * scaled.inverse() * scale.asDiagonal();
  return inverse;
}

// A fault's weight on each sample of an interval whose onset lies u seconds
// after the interval's start, summed against the sample grid's powers:
// g_p = Σ_j s_j^p ω_j, s_j = (j − 1)Δt. A step's ω_j is the share of sample
// j after the onset; a ramp's is the sample's mean of t − t₀ over that share,
// (1/Δt) ∫ (t − t₀) dt, so that a fault a sample grid straddles is weighed as
// the samples themselves carry it (interval means, bench-run format).
Eigen::Vector3d FaultGridSums(int samples, double dt, double u, Regressor fault) {
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  for (int j = 0; j < samples; ++j) {
    const double start = j * dt;
    const double end = start + dt;
    if (end <= u) continue;
    const double from = std::max(start, u);
    const double weight = fault == Regressor::kStep
                              ? (end - from) / dt
                              : 0.5 * ((end - u) * (end - u) - (from - u) * (from - u)) / dt;
    g += weight * Eigen::Vector3d(1.0, start, start * start);
  }
  return g;
}

}  // namespace

NavigationVector FaultColumn(const EpochInterval& e, int sensor_axis, Regressor fault,
                             double onset_s) {
  const auto a = static_cast<Eigen::Index>(sensor_axis);
  const double u = onset_s - e.start_s;
  if (u <= 0.0) {
    if (fault == Regressor::kStep) return e.moments[0].col(a);
    return e.moments[1].col(a) +
           (e.start_s + 0.5 * e.sample_interval_s - onset_s) * e.moments[0].col(a);
  }
  if (onset_s >= e.time_s) return NavigationVector::Zero();
  // The onset inside the interval: the coupling's quadratic in s (header of
  // epoch_run.h, b_j ≈ Σ_p c_p s_j^p, c = μ S⁻¹) summed against the fault's
  // weights. Exact at either end of the interval, where it is μ_0 (or the
  // ramp's column) and 0.
  const int degree = std::min(kCouplingDegree, e.samples - 1);
  const Eigen::Vector3d g = FaultGridSums(e.samples, e.sample_interval_s, u, fault);
  const Eigen::Vector3d x = InverseGram(e.gram, degree) * g;
  NavigationVector column = NavigationVector::Zero();
  for (int p = 0; p <= degree; ++p) column += x[p] * e.moments[static_cast<size_t>(p)].col(a);
  return column;
}

StateGridWeights GridWeights(const Eigen::Matrix2d& d_full, int size, double q,
                             const SensorBlocks::SampleMean& mean, int samples, double dt,
                             const GramMatrix& gram) {
  const int degree = std::min(kCouplingDegree, samples - 1);
  const Eigen::MatrixXd d = d_full.topLeftCorner(size, size);
  // What sample j carries of the block: its first state's mean over the
  // sample, e₀ᵀ(Ψ x_{j−1} + v_j), v_j = G n_j + r_j with r_j independent of
  // the state noise n_j (Cov q·I): G = Cov(v, n)/q, Var r = Var v − G Cov(n, v).
  Eigen::RowVectorXd e = Eigen::RowVectorXd::Zero(size);
  e[0] = 1.0;
  const Eigen::RowVectorXd e_mean = e * mean.transition.topLeftCorner(size, size);
  Eigen::RowVectorXd e_own = Eigen::RowVectorXd::Zero(size);  // e₀ᵀ G
  double own_variance = 0.0;                                  // e₀ᵀ Var r e₀
  if (q > 0.0) {
    e_own = e * mean.cross.topLeftCorner(size, size) / q;
    own_variance = std::max(0.0, mean.noise(0, 0) - q * e_own.squaredNorm());
  }
  // w_p = Σ_j s_j^p e₀ᵀΨ d^{j−1}, s_j = (j − 1)Δt.
  Eigen::MatrixXd w = Eigen::MatrixXd::Zero(kCouplingMoments, size);
  Eigen::RowVectorXd power = e_mean;  // e₀ᵀΨ d^{j−1}
  for (int j = 1; j <= samples; ++j) {
    const double s = (j - 1) * dt;
    double sp = 1.0;
    for (int p = 0; p <= degree; ++p, sp *= s) w.row(p) += sp * power;
    power = power * d;
  }
  // The coefficient of n_i in Σ_j s_j^p (sample j): a_p,i = s_i^p e₀ᵀG + ã_p,i,
  // ã_p,i = s_{i+1}^p e₀ᵀΨ + ã_p,i+1 d (ã_p,M = 0); v_p = Σ_i a_p,i (d^{M−i})ᵀ;
  // U_pr = Σ_i a_p,i a_r,iᵀ, and of r_i, Σ_i s_i^p s_i^r.
  Eigen::MatrixXd a_later = Eigen::MatrixXd::Zero(kCouplingMoments, size);  // ã
  Eigen::MatrixXd v = Eigen::MatrixXd::Zero(kCouplingMoments, size);
  GramMatrix U = GramMatrix::Zero();
  GramMatrix U_own = GramMatrix::Zero();
  Eigen::MatrixXd tail = Eigen::MatrixXd::Identity(size, size);  // d^{M−i}
  Eigen::Matrix<double, kCouplingMoments, 1> powers_i;
  for (int i = samples; i >= 1; --i) {
    if (i < samples) {
      const double s = i * dt;  // s_{i+1}
      double sp = 1.0;
      Eigen::MatrixXd next = a_later * d;
      for (int p = 0; p <= degree; ++p, sp *= s) next.row(p) += sp * e_mean;
      a_later = next;
    }
    powers_i.setZero();
    double sp = 1.0;
    for (int p = 0; p <= degree; ++p, sp *= (i - 1) * dt) powers_i[p] = sp;  // s_i^p
    const Eigen::MatrixXd a = a_later + powers_i * e_own;
    v += a * tail.transpose();
    U += a * a.transpose();
    U_own += powers_i * powers_i.transpose();
    tail = tail * d;
  }
  const GramMatrix S_inv = InverseGram(gram, degree);
  StateGridWeights out;
  out.w.leftCols(size) = S_inv * w;
  out.v.leftCols(size) = q * (S_inv * v);
  const GramMatrix U_tilde = S_inv * (q * U + own_variance * U_own) * S_inv;
  // U is a Gram matrix (positive semidefinite): factor it through its
  // eigenvectors so that tiny negative rounding cannot upset a Cholesky.
  const Eigen::SelfAdjointEigenSolver<GramMatrix> eig(0.5 * (U_tilde + U_tilde.transpose()));
  for (int k = 0; k < kCouplingMoments; ++k) {
    const double lambda = eig.eigenvalues()[k];
    if (lambda > 0.0) out.L.col(k) = eig.eigenvectors().col(k) * std::sqrt(lambda);
  }
  return out;
}

ModelTransitions::ModelTransitions(const ErrorModel& model, const StateLayout& layout, const EpochRun& run)
    : model_(model), layout_(layout), run_(run) {
  const auto& states = layout.sensor_states();
  const SensorBlocks structure = SensorBlocks::Identity(layout);
  for (size_t b = 0; b < structure.blocks.size(); ++b) {
    const SensorBlocks::Block& block = structure.blocks[b];
    const SensorState& s = states[static_cast<size_t>(block.offset)];
    StateSource src;
    src.state = block.offset;
    src.block = static_cast<int>(b);
    src.size = block.size;
    src.axis = SensorAxisIndex(s.sensor, s.axis);
    if (s.dynamics == StateDynamics::kConstant && s.effect >= 0) {
      const ModelEffect& effect = model.effects[static_cast<size_t>(s.effect)];
      if (effect.term.family->kind == EffectKind::kFault) {
        src.fault = effect.term.family->regressor;
        src.onset_s = effect.onset_s;
      } else {
        src.constant_column = run.ConstantColumn(effect.term, s.parameter);
      }
    }
    sources_.push_back(src);
  }
  const int m = layout.sensor_count();
  t_.B.setZero(9, m);
  t_.Qns.setZero(9, m);
  for (int a = 0; a < 3; ++a) {
    white_var_[a] = model.gyro.white_noise_density[a] * model.gyro.white_noise_density[a];
    white_var_[3 + a] = model.acc.white_noise_density[a] * model.acc.white_noise_density[a];
  }
  quantisation_var_ = model.acc.quantization.cwiseAbs2();
  initial_navigation_covariance_ =
      InitialCovariance(model, layout, run).topLeftCorner<StateLayout::kNavigationSize, StateLayout::kNavigationSize>();
}

void ModelTransitions::PrepareGrid(int samples, double dt, const GramMatrix& gram, double interval_s) {
  grid_samples_ = samples;
  grid_dt_ = dt;
  grid_gram_ = gram;
  SensorBlocks d_sample, q_sample;
  SensorBlocks::Discretise(model_, layout_, dt, d_sample, q_sample);
  const std::vector<SensorBlocks::SampleMean> sample_means =
      SensorBlocks::SampleMeans(model_, layout_, dt);
  SensorBlocks::Discretise(model_, layout_, interval_s, D_, Qs_);
  weights_.assign(sources_.size(), StateGridWeights{});
  for (size_t i = 0; i < sources_.size(); ++i) {
    const StateSource& src = sources_[i];
    if (src.constant_column >= 0 || src.fault != Regressor::kNone) continue;
    const auto b = static_cast<size_t>(src.block);
    // The per-sample noise is isotropic in a pair (error_model.h): q = its (0, 0).
    weights_[i] = GridWeights(d_sample.blocks[b].m, src.size, q_sample.blocks[b].m(0, 0),
                              sample_means[b], samples, dt, gram);
  }
}

const IntervalTransition& ModelTransitions::Build(const EpochInterval& e) {
  const double interval_s = e.time_s - e.start_s;
  // The sample times' rounding moves an interval's Gram matrix by parts in
  // 10¹³ from one epoch to the next; the weights it gives differ by as
  // little, and are not worth recomputing (an eigen-decomposition per drift).
  const double gram_change = (e.gram - grid_gram_).cwiseAbs().maxCoeff();
  if (e.samples != grid_samples_ || std::abs(e.sample_interval_s - grid_dt_) > kGridRelativeTolerance * grid_dt_ ||
      !(gram_change <= kGridRelativeTolerance * grid_gram_.cwiseAbs().maxCoeff())) {
    PrepareGrid(e.samples, e.sample_interval_s, e.gram, interval_s);
  }
  t_.A = e.A;
  t_.D = D_;
  t_.Qss = Qs_;
  t_.duration_s = interval_s;
  // The white noise and quantisation summed in packed form, unpacked once.
  PackedSymmetric9d sensor_noise = PackedSymmetric9d::Zero();
  for (int a = 0; a < kSensorAxisCount; ++a) {
    if (white_var_[a] > 0.0)
      sensor_noise.noalias() += white_var_[a] * e.white[static_cast<size_t>(a)];
  }
  for (int a = 0; a < 3; ++a) {
    if (quantisation_var_[a] > 0.0)
      sensor_noise.noalias() += quantisation_var_[a] * e.quantisation[static_cast<size_t>(a)];
  }
  Matrix9d Qnn = Unpack9(sensor_noise);
  for (size_t i = 0; i < sources_.size(); ++i) {
    const StateSource& src = sources_[i];
    if (src.constant_column >= 0) {
      t_.B.col(src.state) = e.constants.col(src.constant_column);
      t_.Qns.col(src.state).setZero();
      continue;
    }
    if (src.fault != Regressor::kNone) {
      t_.B.col(src.state) = FaultColumn(e, src.axis, src.fault, src.onset_s);
      t_.Qns.col(src.state).setZero();
      continue;
    }
    const StateGridWeights& w = weights_[i];
    Eigen::Matrix<double, kNavigationStates, kCouplingMoments> mu;
    for (int p = 0; p < kCouplingMoments; ++p) mu.col(p) = e.moments[static_cast<size_t>(p)].col(src.axis);
    t_.B.middleCols(src.state, src.size).noalias() = mu * w.w.leftCols(src.size);
    t_.Qns.middleCols(src.state, src.size).noalias() = mu * w.v.leftCols(src.size);
    const Eigen::Matrix<double, kNavigationStates, kCouplingMoments> nu = mu * w.L;
    Qnn.noalias() += nu * nu.transpose();
  }
  if (e.starts_segment) {
    // A new segment: its navigation errors start again at the interval's
    // start with the reference's accuracy, independent of the past, and
    // reach the epoch through the interval's own transition.
    Qnn.noalias() += e.A * initial_navigation_covariance_ * e.A.transpose();
    t_.A.setZero();
  }
  t_.Qnn = 0.5 * (Qnn + Qnn.transpose());
  return t_;
}

}  // namespace insdiag::engine
