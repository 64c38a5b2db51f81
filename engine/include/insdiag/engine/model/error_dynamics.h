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
// a run, and so are A = e^{F Δt} and Γ = ∫₀^Δt e^{F s} ds per sample interval
// (their position rows as the mechanisation integrates: DiscretiseNavigation).
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
// The run's samples are condensed into each update interval's Φ and Q once
// per run (filter/epoch_run.h), with C_b^n and the regressors held at their
// mid-sample values within a sample; each model's interval transition is
// then built from the condensed interval (filter/model_transitions.h).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/model/error_model.h"
#include "insdiag/engine/model/state_layout.h"

namespace insdiag::engine {

// The navigation error states lead the state vector: attitude, velocity, position (StateLayout).
inline constexpr int kNavigationStates = StateLayout::kNavigationSize;
using NavigationVector = Eigen::Matrix<double, kNavigationStates, 1>;
using Matrix9d = Eigen::Matrix<double, kNavigationStates, kNavigationStates>;
using Matrix93d = Eigen::Matrix<double, kNavigationStates, 3>;

// F_nav at the site (constant over a bench run).
Matrix9d NavigationErrorMatrix(const Site& site, const StateLayout& layout);

// A = e^{F Δt}, its inverse and Γ = ∫₀^Δt e^{F s} ds, with the position rows
// of the mechanisation's trapezoidal integration (nav/strapdown.h):
//   δr_k = δr_{k−1} + ½Δt (δv_{k−1} + δv_k),  δv_k the velocity rows' value.
// The continuous δṙ = δv differs from it in the third order in Δt: a gyro
// error δω held over a sample moves position by g δω Δt³/4 in the
// mechanisation and g δω Δt³/6 in the continuous equations — a third of the
// gyro's position coupling when an update interval is one sample
// (tests/engine/jacobian_test.cc).
struct NavigationDiscretisation {
  Matrix9d A;
  Matrix9d A_inverse;
  Matrix9d Gamma;
  double dt_s = 0.0;
};
NavigationDiscretisation DiscretiseNavigation(const Matrix9d& F, const StateLayout& layout,
                                              double dt_s);

// Block-diagonal transition (and process noise) of the sensor states: 1×1
// blocks for drifts, constants and random walks, 2×2 for second-order pairs.
class SensorBlocks {
 public:
  struct Block {
    int offset = 0;  // among the sensor states
    int size = 1;
    Eigen::Matrix2d m = Eigen::Matrix2d::Identity();
    bool operator==(const Block& other) const {
      return offset == other.offset && size == other.size && m == other.m;
    }
  };
  std::vector<Block> blocks;

  static SensorBlocks Identity(const StateLayout& layout);
  static SensorBlocks Zero(const StateLayout& layout);
  // Discrete transition D over Δt and the process noise Qs of the model's sensor states.
  static void Discretise(const ErrorModel& model, const StateLayout& layout, double dt_s, SensorBlocks& D,
                         SensorBlocks& Qs);
  // Over one sample of Δt, what a block's state x (ẋ = F x + w, w white of
  // intensity c·I) gives the sample, which carries its mean over the
  // interval (bench-run format):
  //   x(Δt) = D x(0) + n,   m = (1/Δt) ∫₀^Δt x dt = Ψ x(0) + v,
  //   Ψ = (1/Δt) ∫₀^Δt e^{F s} ds,
  // with n and v jointly Gaussian: the covariance of the state augmented by
  // its integral, [ẋ; ẏ] = [F 0; I 0] [x; y] + [w; 0] (Van Loan, IEEE TAC
  // 23(3), 1978). For a random walk of intensity c, Cov(v, n) = cΔt/2 and
  // Var v = cΔt/3 against Var n = cΔt.
  struct SampleMean {
    Eigen::Matrix2d transition = Eigen::Matrix2d::Identity();  // Ψ
    Eigen::Matrix2d cross = Eigen::Matrix2d::Zero();           // Cov(v, n)
    Eigen::Matrix2d noise = Eigen::Matrix2d::Zero();           // Cov(v)
  };
  static std::vector<SampleMean> SampleMeans(const ErrorModel& model, const StateLayout& layout,
                                             double dt_s);

  // M ← M · thisᵀ (columns of M are sensor states).
  void RightMultiplyTranspose(Eigen::Ref<Eigen::MatrixXd> M) const;
  Eigen::MatrixXd Dense(int m) const;
};

// Φ = [A B; 0 D]'s products over blocks held elsewhere: a StateTransition's,
// or a pass's stored transitions (filter/forward_filter.h).
struct TransitionView {
  const Matrix9d& A;
  Eigen::Map<const Eigen::MatrixXd> B;  // 9 × m
  const SensorBlocks& D;

  // x ← Φ x.
  void PropagateMean(Eigen::VectorXd& x) const;
  // M ← Φ M for a matrix with n rows.
  void PropagateRows(Eigen::MatrixXd& M) const;
  // Φ, dense, into `phi`, already n × n (no allocation: for per-epoch loops).
  void WriteDense(Eigen::MatrixXd& phi) const;
};

// The interval's state transition Φ = [A B; 0 D] over a layout of n = 9 + m
// states (A the navigation block, B the sensors' coupling into it, D the
// sensors' own blocks).
struct StateTransition {
  Matrix9d A = Matrix9d::Identity();  // T_M: also maps interval-start coordinates to the end
  Eigen::MatrixXd B;  // 9 × m
  SensorBlocks D;

  // x ← Φ x.
  void PropagateMean(Eigen::VectorXd& x) const;
  // M ← Φ M for a matrix with n rows.
  void PropagateRows(Eigen::MatrixXd& M) const;
  // Φ, dense, n × n.
  Eigen::MatrixXd DenseTransition(int n) const;
  // The same into `phi`, already n × n (no allocation: for per-epoch loops).
  void WriteDense(Eigen::MatrixXd& phi) const;
  TransitionView View() const { return {A, Eigen::Map<const Eigen::MatrixXd>(B.data(), B.rows(), B.cols()), D}; }
};

// The interval's transition and noise, Φ = [A B; 0 D], Q = [Qnn Qns; Qnsᵀ Qss].
struct IntervalTransition : StateTransition {
  Matrix9d Qnn = Matrix9d::Zero();
  Eigen::MatrixXd Qns;  // 9 × m
  SensorBlocks Qss;
  double duration_s = 0.0;

  // P ← Φ P Φᵀ + Q for a full covariance over the layout.
  void PropagateCovariance(Eigen::MatrixXd& P) const;
};

}  // namespace insdiag::engine
