#include "insdiag/engine/model/error_dynamics.h"

#include <cmath>

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

NavigationDiscretisation DiscretiseNavigation(const Matrix9d& F, double dt_s) {
  const auto e = numerics::ExponentialWithIntegral(F, dt_s);
  NavigationDiscretisation d;
  d.A = e.exponential;
  d.A_inverse = numerics::MatrixExponential(-Eigen::MatrixXd(F) * dt_s);
  d.Gamma = e.integral;
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

}  // namespace

SensorBlocks SensorBlocks::Identity(const StateLayout& layout) {
  return StructureOf(layout, Eigen::Matrix2d::Identity());
}

SensorBlocks SensorBlocks::Zero(const StateLayout& layout) { return StructureOf(layout, Eigen::Matrix2d::Zero()); }

void SensorBlocks::Discretise(const ErrorModel& model, const StateLayout& layout, double dt, SensorBlocks& D,
                              SensorBlocks& Qs) {
  D = Identity(layout);
  Qs = Zero(layout);
  const auto& states = layout.sensor_states();
  for (size_t b = 0; b < D.blocks.size(); ++b) {
    const SensorState& s = states[static_cast<size_t>(D.blocks[b].offset)];
    Eigen::Matrix2d& phi = D.blocks[b].m;
    Eigen::Matrix2d& q = Qs.blocks[b].m;
    switch (s.dynamics) {
      case StateDynamics::kGaussMarkov: {
        // Seed eq. 5, exact: φ = e^{−Δt/τ}, q = σ²(1 − φ²).
        const GaussMarkov& gm = (s.sensor == Sensor::kGyro ? model.gyro : model.acc).bias[s.axis];
        const double f = gm.tau_s > 0.0 ? std::exp(-dt / gm.tau_s) : 0.0;
        phi(0, 0) = f;
        q(0, 0) = gm.sigma * gm.sigma * (1.0 - f * f);
        break;
      }
      case StateDynamics::kConstant:
        break;
      case StateDynamics::kRandomWalk: {
        const double k = model.effects[static_cast<size_t>(s.effect)].random_walk_density;
        q(0, 0) = k * k * dt;
        break;
      }
      case StateDynamics::kSecondOrderPair: {
        const ModelEffect& e = model.effects[static_cast<size_t>(s.effect)];
        const double decay = std::exp(-e.second_order_alpha_per_s * dt);
        const double c = std::cos(e.second_order_beta_rad_s * dt);
        const double sn = std::sin(e.second_order_beta_rad_s * dt);
        phi << decay * c, -decay * sn, decay * sn, decay * c;
        q = Eigen::Matrix2d::Identity() * e.second_order_sigma * e.second_order_sigma * (1.0 - decay * decay);
        break;
      }
      case StateDynamics::kSecondOrderTail:
        break;
    }
  }
}

void SensorBlocks::RightMultiplyTranspose(Eigen::Ref<Eigen::MatrixXd> M) const {
  for (const Block& b : blocks) {
    if (b.size == 1) {
      M.col(b.offset) *= b.m(0, 0);
    } else {
      const Eigen::MatrixXd cols = M.middleCols(b.offset, 2) * b.m.transpose();
      M.middleCols(b.offset, 2) = cols;
    }
  }
}

Eigen::MatrixXd SensorBlocks::Dense(int m) const {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(m, m);
  for (const Block& b : blocks) out.block(b.offset, b.offset, b.size, b.size) = b.m.topLeftCorner(b.size, b.size);
  return out;
}

// ---- IntervalTransition -----------------------------------------------------

void IntervalTransition::PropagateMean(Eigen::VectorXd& x) const {
  const auto m = B.cols();
  Eigen::Matrix<double, 9, 1> nav = A * x.head<9>() + B * x.tail(m);
  Eigen::RowVectorXd sensors = x.tail(m).transpose();
  D.RightMultiplyTranspose(sensors);
  x.head<9>() = nav;
  x.tail(m) = sensors.transpose();
}

void IntervalTransition::PropagateRows(Eigen::MatrixXd& M) const {
  const auto m = B.cols();
  Eigen::MatrixXd nav = A * M.topRows<9>() + B * M.bottomRows(m);
  Eigen::MatrixXd sensorsT = M.bottomRows(m).transpose();
  D.RightMultiplyTranspose(sensorsT);
  M.topRows<9>() = nav;
  M.bottomRows(m) = sensorsT.transpose();
}

void IntervalTransition::PropagateCovariance(Eigen::MatrixXd& P) const {
  // Φ P Φᵀ in two one-sided products, then add Q.
  PropagateRows(P);
  Eigen::MatrixXd PT = P.transpose();
  PropagateRows(PT);
  P = PT.transpose();
  const auto m = B.cols();
  P.topLeftCorner<9, 9>() += Qnn;
  P.topRightCorner(9, m) += Qns;
  P.bottomLeftCorner(m, 9) += Qns.transpose();
  for (const auto& b : Qss.blocks) {
    P.block(9 + b.offset, 9 + b.offset, b.size, b.size) += b.m.topLeftCorner(b.size, b.size);
  }
  P = 0.5 * (P + P.transpose()).eval();
}

Eigen::MatrixXd IntervalTransition::DenseTransition(int n) const {
  Eigen::MatrixXd phi = Eigen::MatrixXd::Zero(n, n);
  const int m = n - 9;
  phi.topLeftCorner<9, 9>() = A;
  phi.topRightCorner(9, m) = B;
  phi.bottomRightCorner(m, m) = D.Dense(m);
  return phi;
}

// ---- IntervalAccumulator ----------------------------------------------------

void EvaluateStateRegressors(const ErrorModel& model, const StateLayout& layout, const RegressorInputs& in,
                             Eigen::VectorXd& r) {
  const auto& states = layout.sensor_states();
  double values[2];
  for (size_t i = 0; i < states.size(); ++i) {
    const SensorState& s = states[i];
    if (!s.reaches_output) {
      r[static_cast<Eigen::Index>(i)] = 0.0;
    } else if (s.effect < 0 || s.dynamics != StateDynamics::kConstant) {
      r[static_cast<Eigen::Index>(i)] = 1.0;  // drifts add themselves to the sensor's output
    } else {
      EvaluateRegressor(model.effects[static_cast<size_t>(s.effect)].term, in, values);
      r[static_cast<Eigen::Index>(i)] = values[s.parameter];
    }
  }
}

IntervalAccumulator::IntervalAccumulator(const ErrorModel& model, const StateLayout& layout,
                                         const NavigationDiscretisation& nominal, int samples_per_interval)
    : model_(model), layout_(layout), nominal_dt_(nominal.dt_s) {
  const int m = layout.sensor_count();
  const auto capacity = static_cast<size_t>(std::max(1, samples_per_interval) + 2);
  power_.resize(capacity + 1);
  inverse_power_.resize(capacity + 1);
  att_input_.resize(capacity + 1);
  vel_input_.resize(capacity + 1);
  power_[0].setIdentity();
  inverse_power_[0].setIdentity();
  for (size_t j = 1; j <= capacity; ++j) {
    power_[j] = nominal.A * power_[j - 1];
    inverse_power_[j] = inverse_power_[j - 1] * nominal.A_inverse;
    att_input_[j] = -inverse_power_[j] * nominal.Gamma.middleCols<3>(layout.attitude());
    vel_input_[j] = inverse_power_[j] * nominal.Gamma.middleCols<3>(layout.velocity());
  }
  t_.B.setZero(9, m);
  t_.Qns.setZero(9, m);
  B_y_.setZero(9, m);
  Qns_y_.setZero(9, m);
  regressors_.setZero(m);
  t_.D = SensorBlocks::Identity(layout);
  t_.Qss = SensorBlocks::Zero(layout);
  white_gyro_var_ = model.gyro.white_noise_density.cwiseAbs2();
  white_acc_var_ = model.acc.white_noise_density.cwiseAbs2();
  acc_quantization_var_ = model.acc.quantization.cwiseAbs2();
  Reset();
}

void IntervalAccumulator::Reset() {
  samples_ = 0;
  regular_ = true;
  T_.setIdentity();
  T_inverse_.setIdentity();
  Qnn_half_y_.setZero();
  B_y_.setZero();
  Qns_y_.setZero();
  for (SensorBlocks::Block& b : t_.D.blocks) b.m.setIdentity();
  for (SensorBlocks::Block& b : t_.Qss.blocks) b.m.setZero();
  t_.duration_s = 0.0;
}

const SampleCoupling& IntervalAccumulator::AddSample(const NavigationDiscretisation& nav, const SensorBlocks& D,
                                                     const SensorBlocks& Qs, const Eigen::Matrix3d& C_mid,
                                                     const RegressorInputs& inputs) {
  ++samples_;
  const auto j = static_cast<size_t>(samples_);
  const bool nominal_step = std::abs(nav.dt_s - nominal_dt_) <= 1e-9 * nominal_dt_;
  if (regular_ && (!nominal_step || j >= power_.size())) {
    // Leave the tables: carry T_{j−1} and its inverse explicitly from here on.
    T_ = power_[j - 1];
    T_inverse_ = inverse_power_[j - 1];
    regular_ = false;
  }
  SampleCoupling& c = coupling_;
  if (regular_) {
    c.g_att.noalias() = att_input_[j].lazyProduct(C_mid);
    c.g_vel.noalias() = vel_input_[j].lazyProduct(C_mid);
  } else {
    const Matrix9d T = nav.A.lazyProduct(T_);  // lazy products must not alias their operands
    const Matrix9d T_inverse = T_inverse_.lazyProduct(nav.A_inverse);
    T_ = T;
    T_inverse_ = T_inverse;
    const Matrix93d att = -T_inverse_.lazyProduct(nav.Gamma.middleCols<3>(layout_.attitude()));
    const Matrix93d vel = T_inverse_.lazyProduct(nav.Gamma.middleCols<3>(layout_.velocity()));
    c.g_att.noalias() = att.lazyProduct(C_mid);
    c.g_vel.noalias() = vel.lazyProduct(C_mid);
  }
  c.inputs = inputs;
  c.dt_s = nav.dt_s;

  EvaluateStateRegressors(model_, layout_, inputs, regressors_);
  const auto& states = layout_.sensor_states();

  // In interval-start coordinates the navigation transition is the identity:
  //   Qnn ← Qnn + X + Xᵀ + Qw,   X = (Qns + ½ B_j Qss) B_jᵀ
  //   Qns ← (Qns + B_j Qss) Dᵀ,   Qss ← D Qss Dᵀ + Qs
  //   B   ← B + B_j D_acc,        D_acc ← D D_acc
  // (the sample acts on the sensor states as they stand at its start).
  // B_j's column s is g_{sensor(s)}[:, axis(s)]·r_s, so X = Y_g g_attᵀ + Y_a g_velᵀ with
  // Y_{g|a}[:, axis] = Σ_s (Qns + ½ B_j Qss)[:, s]·r_s over the gyro | accelerometer states.
  // The white noise Qw = g_att W_g g_attᵀ + g_vel W_a g_velᵀ (W = N²/Δt, interval
  // means of the white sensor noise over the sample) joins X as ½ g W: only
  // the half H = Σ_j (Z_g g_attᵀ + Z_a g_velᵀ), Z = Y + ½ g W, is accumulated,
  // and Qnn = H + Hᵀ at Finish() — one 9×6·6×9 product a sample instead of four.
  const double half_inv_dt = 0.5 / c.dt_s;
  Matrix93d Zg = c.g_att * (white_gyro_var_ * half_inv_dt).asDiagonal();
  Matrix93d Za = c.g_vel * (white_acc_var_ * half_inv_dt).asDiagonal();
  auto z_column = [&](const SensorState& st) { return (st.sensor == Sensor::kGyro ? Zg : Za).col(st.axis); };
  // Every term is block-diagonal in the sensor states: one pass over the
  // blocks, scalar for drifts, walks and constants, 2×2 for a second-order pair.
  for (size_t k = 0; k < D.blocks.size(); ++k) {
    const SensorBlocks::Block& d = D.blocks[k];
    const SensorBlocks::Block& q = Qs.blocks[k];
    SensorBlocks::Block& qss = t_.Qss.blocks[k];
    SensorBlocks::Block& d_acc = t_.D.blocks[k];
    const int s = d.offset;
    if (d.size == 1) {
      const SensorState& st = states[static_cast<size_t>(s)];
      const double r = regressors_[s];
      const Eigen::Matrix<double, 9, 1> bj = c.Column(st.sensor, st.axis) * r;
      auto qns = Qns_y_.col(s);
      z_column(st) += (qns + (0.5 * qss.m(0, 0)) * bj) * r;
      qns = (qns + qss.m(0, 0) * bj) * d.m(0, 0);
      B_y_.col(s) += bj * d_acc.m(0, 0);
      qss.m(0, 0) = d.m(0, 0) * d.m(0, 0) * qss.m(0, 0) + q.m(0, 0);
      d_acc.m(0, 0) *= d.m(0, 0);
    } else {
      Eigen::Matrix<double, 9, 2> bj;
      for (int i = 0; i < 2; ++i) {
        const SensorState& st = states[static_cast<size_t>(s + i)];
        bj.col(i) = c.Column(st.sensor, st.axis) * regressors_[s + i];
      }
      const Eigen::Matrix<double, 9, 2> v = bj * qss.m;  // B_j Qss
      for (int i = 0; i < 2; ++i) {
        z_column(states[static_cast<size_t>(s + i)]) += (Qns_y_.col(s + i) + 0.5 * v.col(i)) * regressors_[s + i];
      }
      const Eigen::Matrix<double, 9, 2> qns = (Qns_y_.middleCols<2>(s) + v) * d.m.transpose();
      Qns_y_.middleCols<2>(s) = qns;
      B_y_.middleCols<2>(s) += bj * d_acc.m;
      qss.m = d.m * qss.m * d.m.transpose() + q.m;
      d_acc.m = d.m * d_acc.m;
    }
  }
  // Eigen sends even fixed 9×9 products to its blocked GEMM (its coefficient-based
  // threshold is rows + cols + depth < 20); lazyProduct keeps them inline.
  Qnn_half_y_.noalias() += Zg.lazyProduct(c.g_att.transpose());
  Qnn_half_y_.noalias() += Za.lazyProduct(c.g_vel.transpose());
  if (acc_quantization_var_.maxCoeff() > 0.0) {
    // Velocity quantisation: the position integrates each sample's carried
    // remainder, white with variance Q² per axis (IEEE Std 952, Annex C).
    const Matrix93d to_position =
        (regular_ ? inverse_power_[j] : T_inverse_).middleCols<3>(layout_.position()) * C_mid;
    Qnn_half_y_.noalias() += (to_position * (acc_quantization_var_ * (0.5 * c.dt_s * c.dt_s)).asDiagonal())
                                 .lazyProduct(to_position.transpose());
  }
  t_.duration_s += c.dt_s;
  return c;
}

const IntervalTransition& IntervalAccumulator::Finish() {
  const Matrix9d& T = regular_ ? power_[static_cast<size_t>(samples_)] : T_;
  t_.A = T;
  t_.B.noalias() = T.lazyProduct(B_y_);
  t_.Qns.noalias() = T.lazyProduct(Qns_y_);
  const Matrix9d TH = T.lazyProduct(Qnn_half_y_);
  const Matrix9d half = TH.lazyProduct(T.transpose());
  t_.Qnn = half + half.transpose();
  return t_;
}

}  // namespace insdiag::engine
