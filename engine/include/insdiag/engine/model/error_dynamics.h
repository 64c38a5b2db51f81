// Linearised INS error dynamics on the bench and their exact discretisation
// over a filter interval (seed eq. 3–4: ẋ = A(t)x + G(t)ξ).
//
// Navigation errors (phi-angle form, NED; Titterton & Weston, Strapdown
// Inertial Navigation Technology, 2nd ed., ch. 12), linearised about the
// bench's true trajectory — the site, zero velocity, f^n = −g^n:
//
//   ψ̇  = −[ω_ie^n×] ψ + δω_ie^n + δω_en^n − C_b^n δω^b
//   δv̇ = [f^n×] ψ − [2ω_ie^n×] δv + δg^n + C_b^n δf^b
//   δṙ = δv                                          (NED metres)
// with δω_ie^n = Ω [−sin φ, 0, −cos φ]ᵀ δr_N/(R_M+h),
//      δω_en^n = [δv_E/(R_N+h), −δv_N/(R_M+h), −δv_E tan φ/(R_N+h)]ᵀ,
//      δg_D    = −(∂γ/∂h) δr_D  (the vertical-channel instability; the
//                 latitude term ∂γ/∂φ·δφ, below 1e−8 m/s² per metre, is left out).
// Because the bench trajectory is fixed, the 9×9 matrix F_nav is constant for
// a run, and so are A = e^{F Δt} and Γ = ∫₀^Δt e^{F s} ds per sample interval.
//
// Sensor errors δω^b, δf^b = Σ_s r_s(u)·x_s over the sensor states s of the
// layout (r_s = 1 for drifts, the catalogue regressor for constant effects),
// held over each sample interval. Over sample j (Δt):
//
//   x_nav ← A x_nav + B_j x_sens + noise,   B_j = [g_att | g_vel] selected by each
//           state's sensor and axis, times r_s,  g_att = −Γ_{:,ψ} C_b^n,  g_vel = Γ_{:,δv} C_b^n
//   x_sens ← D x_sens + w,                   D, E[wwᵀ] block diagonal (error_model.h)
//   white sensor noise n_g, n_a: E[n nᵀ] = N²/Δt per axis, entering through g_att, g_vel.
//
// IntervalAccumulator composes these per-sample maps into the interval's
// Φ = [A_acc B_acc; 0 D_acc] and Q, exactly (no approximation beyond holding
// C_b^n and the regressors at their mid-interval values within a sample).
// It accumulates in coordinates pulled back to the interval's start,
// y = T_j⁻¹ x with T_j = A_j ⋯ A_1: there the navigation transition is the
// identity and each sample adds only its low-rank terms, with T_j⁻¹Γ taken
// from tables for the run's nominal step; Finish() maps back with T_M.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/model/error_model.h"
#include "insdiag/engine/model/state_layout.h"

namespace insdiag::engine {

using Matrix9d = Eigen::Matrix<double, 9, 9>;
using Matrix93d = Eigen::Matrix<double, 9, 3>;

// F_nav at the site (constant over a bench run).
Matrix9d NavigationErrorMatrix(const Site& site, const StateLayout& layout);

// A = e^{F Δt}, its inverse and Γ = ∫₀^Δt e^{F s} ds.
struct NavigationDiscretisation {
  Matrix9d A;
  Matrix9d A_inverse;
  Matrix9d Gamma;
  double dt_s = 0.0;
};
NavigationDiscretisation DiscretiseNavigation(const Matrix9d& F, double dt_s);

// How one sample couples sensor errors into the navigation errors, in the
// interval-start coordinates of the accumulator: a sensor error e held over
// the sample adds T_j⁻¹·(g_att|g_vel)·e to y (T_M maps it to the interval's end).
struct SampleCoupling {
  Matrix93d g_att;  // per unit rad/s of gyro error:  −T_j⁻¹ Γ_{:,ψ} C_b^n
  Matrix93d g_vel;  // per unit m/s² of accelerometer error: T_j⁻¹ Γ_{:,δv} C_b^n
  RegressorInputs inputs;
  double dt_s = 0.0;

  // The column a sensor error on (sensor, axis) adds, per unit.
  auto Column(Sensor sensor, int axis) const {
    return sensor == Sensor::kGyro ? g_att.col(axis) : g_vel.col(axis);
  }
};

// Block-diagonal transition (and process noise) of the sensor states: 1×1
// blocks for drifts, constants and random walks, 2×2 for second-order pairs.
class SensorBlocks {
 public:
  struct Block {
    int offset = 0;  // among the sensor states
    int size = 1;
    Eigen::Matrix2d m = Eigen::Matrix2d::Identity();
  };
  std::vector<Block> blocks;

  static SensorBlocks Identity(const StateLayout& layout);
  static SensorBlocks Zero(const StateLayout& layout);
  // Discrete transition D over Δt and the process noise Qs of the model's sensor states.
  static void Discretise(const ErrorModel& model, const StateLayout& layout, double dt_s, SensorBlocks& D,
                         SensorBlocks& Qs);

  // M ← M · thisᵀ (columns of M are sensor states).
  void RightMultiplyTranspose(Eigen::Ref<Eigen::MatrixXd> M) const;
  Eigen::MatrixXd Dense(int m) const;
};

// The interval's transition and noise, Φ = [A B; 0 D], Q = [Qnn Qns; Qnsᵀ Qss].
struct IntervalTransition {
  Matrix9d A = Matrix9d::Identity();  // T_M: also maps interval-start coordinates to the end
  Eigen::MatrixXd B;  // 9 × m
  SensorBlocks D;
  Matrix9d Qnn = Matrix9d::Zero();
  Eigen::MatrixXd Qns;  // 9 × m
  SensorBlocks Qss;
  double duration_s = 0.0;

  // P ← Φ P Φᵀ + Q for a full covariance over the layout.
  void PropagateCovariance(Eigen::MatrixXd& P) const;
  // x ← Φ x.
  void PropagateMean(Eigen::VectorXd& x) const;
  // M ← Φ M for a matrix with n rows.
  void PropagateRows(Eigen::MatrixXd& M) const;
  Eigen::MatrixXd DenseTransition(int n) const;
};

// Accumulates the per-sample maps of one filter interval. Preallocated: no
// allocation per sample.
class IntervalAccumulator {
 public:
  // `nominal` is the run's regular sample step; `samples_per_interval` sizes its tables.
  IntervalAccumulator(const ErrorModel& model, const StateLayout& layout, const NavigationDiscretisation& nominal,
                      int samples_per_interval);

  void Reset();
  // Adds one sample of step `nav` (the nominal one or an irregular one) and
  // returns its coupling in interval-start coordinates.
  const SampleCoupling& AddSample(const NavigationDiscretisation& nav, const SensorBlocks& D, const SensorBlocks& Qs,
                                  const Eigen::Matrix3d& C_b_n_mid, const RegressorInputs& inputs);
  // The interval's Φ and Q in end coordinates (valid until the next Reset).
  const IntervalTransition& Finish();
  const Eigen::VectorXd& regressors() const { return regressors_; }

 private:
  const ErrorModel& model_;
  const StateLayout& layout_;
  // Tables for the nominal step, j = 0 … capacity: A^j, −A^{−j}Γ_{:,ψ}, A^{−j}Γ_{:,δv}.
  std::vector<Matrix9d> power_, inverse_power_;
  std::vector<Matrix93d> att_input_, vel_input_;
  double nominal_dt_ = 0.0;
  // Samples so far; while every step is nominal the tables hold T_j, else T_ and T_inverse_.
  int samples_ = 0;
  bool regular_ = true;
  Matrix9d T_, T_inverse_;
  SampleCoupling coupling_;
  IntervalTransition t_;
  Matrix9d Qnn_half_y_;  // H: Qnn = H + Hᵀ in interval-start coordinates
  Eigen::MatrixXd B_y_, Qns_y_;  // 9 × m, interval-start coordinates
  Eigen::VectorXd regressors_;   // r_s of the last sample
  Eigen::Vector3d white_gyro_var_, white_acc_var_, acc_quantization_var_;
};

// r_s(u) of every sensor state for one sample's inputs.
void EvaluateStateRegressors(const ErrorModel& model, const StateLayout& layout, const RegressorInputs& in,
                             Eigen::VectorXd& r);

}  // namespace insdiag::engine
