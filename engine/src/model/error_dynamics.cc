#include "insdiag/engine/model/error_dynamics.h"

#include <cmath>

#include "insdiag/engine/model/flicker_floor.h"
#include "insdiag/engine/nav/rotation.h"
#include "insdiag/engine/nav/strapdown.h"
#include "insdiag/engine/nav/wgs84.h"
#include "insdiag/engine/numerics/matrix_exponential.h"

namespace insdiag::engine {

Matrix9d NavigationErrorMatrix(const Site& site, const StateLayout& layout) {
  const double lat = site.latitude_rad;
  const double h = site.height_m;
  const double rm = wgs84::MeridianRadiusM(lat) + h;
  const double rn = wgs84::PrimeVerticalRadiusM(lat) + h;
  const double omega = wgs84::kEarthRateRadS;
  const Eigen::Vector3d w_ie = wgs84::EarthRateNed(lat);
  const Eigen::Vector3d f_n = -nav::GravityNed(lat, h);
  // ∂γ/∂h from the WGS-84 height expansion (wgs84.h): γ0 (−2/a (1 + f + m − 2 f sin²φ) + 6h/a²).
  const double s2 = std::pow(std::sin(lat), 2);
  const double a = wgs84::kSemiMajorAxisM;
  const double gamma0 = wgs84::NormalGravityMps2(lat, 0.0);
  const double dgamma_dh =
      gamma0 * (-2.0 / a * (1.0 + wgs84::kFlattening + wgs84::kGravityRatioM - 2.0 * wgs84::kFlattening * s2) +
                6.0 * h / (a * a));

  const int att = layout.attitude();
  const int vel = layout.velocity();
  const int pos = layout.position();
  Matrix9d F = Matrix9d::Zero();
  // Attitude rows.
  F.block<3, 3>(att, att) = -nav::Skew(w_ie);
  F(att + 0, pos + 0) = -omega * std::sin(lat) / rm;
  F(att + 2, pos + 0) = -omega * std::cos(lat) / rm;
  F(att + 0, vel + 1) = 1.0 / rn;
  F(att + 1, vel + 0) = -1.0 / rm;
  F(att + 2, vel + 1) = -std::tan(lat) / rn;
  // Velocity rows.
  F.block<3, 3>(vel, att) = nav::Skew(f_n);
  F.block<3, 3>(vel, vel) = -nav::Skew(2.0 * w_ie);
  F(vel + 2, pos + 2) = -dgamma_dh;
  // Position rows.
  F.block<3, 3>(pos, vel) = Eigen::Matrix3d::Identity();
  return F;
}

NavigationDiscretisation DiscretiseNavigation(const Matrix9d& F, const StateLayout& layout,
                                              double dt_s) {
  const auto e = numerics::ExponentialWithIntegral(F, dt_s);
  NavigationDiscretisation d;
  d.A = e.exponential;
  d.Gamma = e.integral;
  // Position rows as the mechanisation integrates them: the trapezoid of the
  // sample's start and end velocities (header).
  const int vel = layout.velocity();
  const int pos = layout.position();
  d.A.middleRows<3>(pos) = 0.5 * dt_s * d.A.middleRows<3>(vel);
  d.A.block<3, 3>(pos, vel) += 0.5 * dt_s * Eigen::Matrix3d::Identity();
  d.A.block<3, 3>(pos, pos) += Eigen::Matrix3d::Identity();
  d.Gamma.middleRows<3>(pos) = 0.5 * dt_s * d.Gamma.middleRows<3>(vel);
  d.A_inverse = d.A.inverse();
  d.dt_s = dt_s;
  return d;
}

// ---- SensorBlocks -----------------------------------------------------------

namespace {

SensorBlocks StructureOf(const StateLayout& layout, const Eigen::Matrix2d& fill) {
  SensorBlocks b;
  const auto& states = layout.sensor_states();
  for (size_t i = 0; i < states.size(); ++i) {
    if (states[i].dynamics == StateDynamics::kSecondOrderTail) continue;
    const int size = states[i].dynamics == StateDynamics::kSecondOrderPair ? 2 : 1;
    b.blocks.push_back({static_cast<int>(i), size, fill});
  }
  return b;
}

// Every sensor block's continuous dynamics, ẋ = F x + w with w white of
// intensity c·I, is a damped rotation F = −α I + β J (J = [0 −1; 1 0]; a
// 1×1 block has β = 0):
//   Gauss–Markov drift (seed eq. 5)  ḃ = −b/τ + w     α = 1/τ, c = 2σ²/τ
//   a flicker floor's component       likewise, its σ_c and T_j (model/flicker_floor.h)
//   random walk                      ḃ = w            α = 0,   c = K²
//   a transient's start value        ḃ = −b/τ         α = 1/τ, c = 0
//   second-order pair                                 α, β,    c = 2ασ²
//   constant                                          α = 0,   c = 0
// so that both the discrete transition and the sample means follow from one
// description of the model's parameters.
struct ContinuousBlock {
  double alpha_per_s = 0.0;
  double beta_rad_s = 0.0;
  double intensity = 0.0;  // c
};

ContinuousBlock ContinuousDynamics(const ErrorModel& model, const SensorState& s) {
  switch (s.dynamics) {
    case StateDynamics::kGaussMarkov: {
      const GaussMarkov& gm = (s.sensor == Sensor::kGyro ? model.gyro : model.acc).bias[s.axis];
      if (!(gm.tau_s > 0.0))
        return {};  // σ = 0 too (ErrorModel::Validate): a state that stays zero
      return {1.0 / gm.tau_s, 0.0, 2.0 * gm.sigma * gm.sigma / gm.tau_s};
    }
    case StateDynamics::kFlickerComponent: {
      const GaussMarkov c = FlickerComponentOf(model, s.sensor, s.axis, s.parameter);
      return {1.0 / c.tau_s, 0.0, 2.0 * c.sigma * c.sigma / c.tau_s};
    }
    case StateDynamics::kRandomWalk: {
      const double k = model.effects[static_cast<size_t>(s.effect)].random_walk_density;
      return {0.0, 0.0, k * k};
    }
    case StateDynamics::kSecondOrderPair: {
      const ModelEffect& e = model.effects[static_cast<size_t>(s.effect)];
      const double alpha = e.second_order_alpha_per_s;
      return {alpha, e.second_order_beta_rad_s,
              2.0 * alpha * e.second_order_sigma * e.second_order_sigma};
    }
    case StateDynamics::kDecaying:
      return {1.0 / model.effects[static_cast<size_t>(s.effect)].time_constant_s, 0.0, 0.0};
    case StateDynamics::kConstant:
    case StateDynamics::kSecondOrderTail:
      break;
  }
  return {};
}

Eigen::Matrix2d DriftMatrix(const ContinuousBlock& c) {
  Eigen::Matrix2d F;
  F << -c.alpha_per_s, -c.beta_rad_s, c.beta_rad_s, -c.alpha_per_s;
  return F;
}

// The exact discretisation over Δt: φ = e^{FΔt} = e^{−αΔt} R(βΔt) and,
// since F + Fᵀ = −2αI, q = ∫₀^Δt e^{Fs} c e^{Fᵀs} ds = c (1 − e^{−2αΔt})/(2α) I
// (c Δt where α = 0).
void DiscretiseBlock(const ContinuousBlock& c, double dt, Eigen::Matrix2d& phi,
                     Eigen::Matrix2d& q) {
  const double decay = std::exp(-c.alpha_per_s * dt);
  const double cosine = std::cos(c.beta_rad_s * dt), sine = std::sin(c.beta_rad_s * dt);
  phi << decay * cosine, -decay * sine, decay * sine, decay * cosine;
  const double variance =
      c.alpha_per_s > 0.0
          ? c.intensity * -std::expm1(-2.0 * c.alpha_per_s * dt) / (2.0 * c.alpha_per_s)
          : c.intensity * dt;
  q = variance * Eigen::Matrix2d::Identity();
}

SensorBlocks::SampleMean SampleMeanOf(const ContinuousBlock& block, int n, double dt) {
  // The state and its integral: A = [F 0; I 0], noise [I; 0] c [I 0].
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  A.topLeftCorner(n, n) = DriftMatrix(block).topLeftCorner(n, n);
  A.bottomLeftCorner(n, n).setIdentity();
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  W.topLeftCorner(n, n).setIdentity();
  W *= block.intensity;
  // Van Loan: exp([−A W; 0 Aᵀ] Δt) = [· X12; 0 X22], Φ = X22ᵀ, Q = Φ X12.
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(4 * n, 4 * n);
  M.topLeftCorner(2 * n, 2 * n) = -A * dt;
  M.topRightCorner(2 * n, 2 * n) = W * dt;
  M.bottomRightCorner(2 * n, 2 * n) = A.transpose() * dt;
  const Eigen::MatrixXd E = numerics::MatrixExponential(M);
  const Eigen::MatrixXd phi = E.bottomRightCorner(2 * n, 2 * n).transpose();
  const Eigen::MatrixXd Q = phi * E.topRightCorner(2 * n, 2 * n);
  SensorBlocks::SampleMean out;
  out.transition.topLeftCorner(n, n) = phi.bottomLeftCorner(n, n) / dt;
  out.cross.topLeftCorner(n, n) = Q.bottomLeftCorner(n, n) / dt;
  out.noise.topLeftCorner(n, n) =
      0.5 * (Q.bottomRightCorner(n, n) + Q.bottomRightCorner(n, n).transpose()) / (dt * dt);
  return out;
}

}  // namespace

SensorBlocks SensorBlocks::Identity(const StateLayout& layout) {
  return StructureOf(layout, Eigen::Matrix2d::Identity());
}

SensorBlocks SensorBlocks::Zero(const StateLayout& layout) {
  return StructureOf(layout, Eigen::Matrix2d::Zero());
}

void SensorBlocks::Discretise(const ErrorModel& model, const StateLayout& layout, double dt,
                              SensorBlocks& D, SensorBlocks& Qs) {
  D = Identity(layout);
  Qs = Zero(layout);
  const auto& states = layout.sensor_states();
  for (size_t b = 0; b < D.blocks.size(); ++b) {
    const SensorState& s = states[static_cast<size_t>(D.blocks[b].offset)];
    DiscretiseBlock(ContinuousDynamics(model, s), dt, D.blocks[b].m, Qs.blocks[b].m);
  }
}

std::vector<SensorBlocks::SampleMean> SensorBlocks::SampleMeans(const ErrorModel& model,
                                                                const StateLayout& layout,
                                                                double dt) {
  const SensorBlocks blocks = Identity(layout);
  const auto& states = layout.sensor_states();
  std::vector<SampleMean> out(blocks.blocks.size());
  for (size_t b = 0; b < blocks.blocks.size(); ++b) {
    const Block& block = blocks.blocks[b];
    const ContinuousBlock continuous =
        ContinuousDynamics(model, states[static_cast<size_t>(block.offset)]);
    const bool moves =
        continuous.intensity > 0.0 || continuous.alpha_per_s != 0.0 || continuous.beta_rad_s != 0.0;
    if (moves) out[b] = SampleMeanOf(continuous, block.size, dt);
  }
  return out;
}

void SensorBlocks::RightMultiplyTranspose(Eigen::Ref<Eigen::MatrixXd> M) const {
  for (const Block& b : blocks) {
    if (b.size == 1) {
      M.col(b.offset) *= b.m(0, 0);
    } else {
      // A pair's two columns, row by row: in place, with no temporary.
      const Eigen::Matrix2d mt = b.m.topLeftCorner<2, 2>().transpose();
      for (Eigen::Index i = 0; i < M.rows(); ++i) {
        const Eigen::RowVector2d row = M.block<1, 2>(i, b.offset);
        M.block<1, 2>(i, b.offset).noalias() = row * mt;
      }
    }
  }
}

Eigen::MatrixXd SensorBlocks::Dense(int m) const {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(m, m);
  for (const Block& b : blocks) out.block(b.offset, b.offset, b.size, b.size) = b.m.topLeftCorner(b.size, b.size);
  return out;
}

// ---- StateTransition, IntervalTransition ------------------------------------

void TransitionView::PropagateMean(Eigen::VectorXd& x) const {
  // Scratch per thread, sized once per pass: this runs every epoch.
  thread_local Eigen::RowVectorXd sensors;
  const auto m = B.cols();
  NavigationVector nav = A * x.head<kNavigationStates>();
  nav.noalias() += B * x.tail(m);
  sensors = x.tail(m).transpose();
  D.RightMultiplyTranspose(sensors);
  x.head<kNavigationStates>() = nav;
  x.tail(m) = sensors.transpose();
}

void TransitionView::PropagateRows(Eigen::MatrixXd& M) const {
  // Scratch per thread, sized once per pass: this runs every epoch of every
  // forward and backward pass.
  thread_local Eigen::MatrixXd nav, sensors_t;
  const auto m = B.cols();
  nav.noalias() = A * M.topRows<kNavigationStates>();
  nav.noalias() += B * M.bottomRows(m);
  sensors_t = M.bottomRows(m).transpose();
  D.RightMultiplyTranspose(sensors_t);
  M.topRows<kNavigationStates>() = nav;
  M.bottomRows(m) = sensors_t.transpose();
}

void TransitionView::WriteDense(Eigen::MatrixXd& phi) const {
  phi.setZero();
  phi.topLeftCorner<kNavigationStates, kNavigationStates>() = A;
  if (B.cols() == 0) return;
  phi.topRightCorner(9, B.cols()) = B;
  for (const SensorBlocks::Block& b : D.blocks) {
    phi.block(9 + b.offset, 9 + b.offset, b.size, b.size) = b.m.topLeftCorner(b.size, b.size);
  }
}

void StateTransition::PropagateMean(Eigen::VectorXd& x) const { View().PropagateMean(x); }

void StateTransition::PropagateRows(Eigen::MatrixXd& M) const { View().PropagateRows(M); }

void IntervalTransition::PropagateCovariance(Eigen::MatrixXd& P) const {
  // Φ P Φᵀ in two one-sided products, then add Q. Scratch per thread: this
  // runs every epoch of every pass.
  thread_local Eigen::MatrixXd half;
  PropagateRows(P);      // Φ P
  half = P.transpose();  // P Φᵀ
  PropagateRows(half);   // Φ P Φᵀ (symmetric but for rounding, evened out below)
  P = half;
  const auto m = B.cols();
  P.topLeftCorner<kNavigationStates, kNavigationStates>() += Qnn;
  P.topRightCorner(9, m) += Qns;
  P.bottomLeftCorner(m, 9) += Qns.transpose();
  for (const auto& b : Qss.blocks) {
    P.block(9 + b.offset, 9 + b.offset, b.size, b.size) += b.m.topLeftCorner(b.size, b.size);
  }
  for (Eigen::Index j = 1; j < P.cols(); ++j) {
    for (Eigen::Index i = 0; i < j; ++i) P(i, j) = P(j, i) = 0.5 * (P(i, j) + P(j, i));
  }
}

Eigen::MatrixXd StateTransition::DenseTransition(int n) const {
  Eigen::MatrixXd phi(n, n);
  WriteDense(phi);
  return phi;
}

void StateTransition::WriteDense(Eigen::MatrixXd& phi) const { View().WriteDense(phi); }

}  // namespace insdiag::engine
