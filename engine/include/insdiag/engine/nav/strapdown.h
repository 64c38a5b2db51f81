// Strapdown mechanisation in the local North-East-Down frame on the WGS-84
// ellipsoid: the navigation kernel that turns body increments into attitude,
// velocity and position.
//
// One step over the sample interval (t[k−1], t[k]] with body increments
// Δθ_k = ω̃·Δt [rad] and Δv_k = f̃·Δt [m/s] (Savage, "Strapdown Inertial
// Navigation Integration Algorithm Design", J. Guidance Control Dyn. 21(1–2),
// 1998, two-sample forms with the previous interval's increments):
//
//   φ_k   = Δθ_k + (1/12) Δθ_{k−1} × Δθ_k                       coning-corrected rotation vector
//   Δv_b  = (J/h)⁻¹ Δv_k − (1/12)(Δθ_k − Δθ_{k−1}) × Δv_k
//           J/h = I − a [u×] + b [u×]²,  θ = |Δθ_k|, u = Δθ_k/θ,
//           a = (1 − cos θ)/θ,  b = (θ − sin θ)/θ                rotation compensation
//
// The compensation is exact for rotation at a constant rate with the specific
// force fixed in the navigation frame — a rotary table's motion: then
// Δv = J f₀ with J = ∫₀^h e^{−[ω×]t} dt (Rodrigues' formula integrated), and
// the increment wanted is h f₀ = h J⁻¹ Δv = (I + ½[Δθ×] + (1/12)[Δθ×]² + …) Δv.
// Truncated forms leave a residual that turns with the body and builds up over
// each half turn (1e-3 m/s at 10°/s and 10 Hz for the second-order form); the
// previous-interval sculling term, designed for vibration, doubles the
// O(Δθ²) residual instead (a scale-factor-like error of Δθ²/6 on the axes
// turning through gravity: 2 ppm at 10°/s and 50 Hz). While the table's rate
// ramps (θ(t) = ω₀t + ½αt²) the remainder is (αh³/12) × f₀ to first order;
// αh² ≈ Δθ_k − Δθ_{k−1} gives the second term (1.4e-3 m/s over a one-second
// 10°/s² ramp at 10 Hz without it).
//   ζ     = (ω_ie^n + ω_en^n) Δt                                 navigation-frame rotation
//   C_b^n(k) = C(−ζ) · C_b^n(k−1) · C(φ_k)
//   v^n(k)   = v^n(k−1) + (I − ½[ζ×]) C_b^n(k−1) Δv_b + (g^n − (2ω_ie^n + ω_en^n) × v^n) Δt
//   h(k)     = h(k−1) − ½ (v_D(k−1) + v_D(k)) Δt                  trapezoidal position
//   φ(k)     = φ(k−1) + ½ (v_N(k−1) + v_N(k)) Δt / (R_M + h)
//   λ(k)     = λ(k−1) + ½ (v_E(k−1) + v_E(k)) Δt / ((R_N + h) cos φ)
//
// g^n = [0, 0, γ(φ, h)] with γ the WGS-84 normal gravity (wgs84.h);
// ω_en^n = [v_E/(R_N+h), −v_N/(R_M+h), −v_E tan φ/(R_N+h)].
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace insdiag::engine::nav {

struct NavState {
  Eigen::Quaterniond q_b_n = Eigen::Quaterniond::Identity();  // C_b^n
  Eigen::Vector3d v_n_mps = Eigen::Vector3d::Zero();          // velocity w.r.t. Earth, NED
  double latitude_rad = 0.0;
  double longitude_rad = 0.0;
  double height_m = 0.0;
};

// Body increments over one sample interval.
struct ImuIncrement {
  Eigen::Vector3d dtheta_rad = Eigen::Vector3d::Zero();  // ∫ω_ib^b dt
  Eigen::Vector3d dv_mps = Eigen::Vector3d::Zero();      // ∫f^b dt
};

// Advances `state` over one interval of `dt_s` seconds with the current and
// the previous interval's increments (zero `previous` at the first step).
NavState PropagateStrapdown(const NavState& state, const ImuIncrement& current,
                            const ImuIncrement& previous, double dt_s);

// J/h = (1/h)∫₀^h e^{−[ω×]t} dt for a rotation Δθ = ωh at a constant rate: the
// interval mean of a navigation-frame-fixed vector seen in the turning body,
// relative to its value in the frame at the interval's start (see above).
Eigen::Matrix3d MeanBodyRotation(const Eigen::Vector3d& dtheta_rad);

// (J/h)⁻¹ Δv: the velocity increment in the frame at the interval's start (see above).
Eigen::Vector3d UnrotateVelocityIncrement(const Eigen::Vector3d& dtheta_rad, const Eigen::Vector3d& dv_mps);

// Transport rate ω_en^n [rad/s] for the velocity and position of `state`.
Eigen::Vector3d TransportRateNed(const NavState& state);

// Gravity vector g^n = [0, 0, γ(φ, h)] [m/s²].
Eigen::Vector3d GravityNed(double latitude_rad, double height_m);

}  // namespace insdiag::engine::nav
