// Strapdown mechanisation in the local North-East-Down frame on the WGS-84
// ellipsoid: the navigation kernel that turns body increments into attitude,
// velocity and position.
//
// One step over the sample interval (t[k−1], t[k]] with body increments
// Δθ_k = ω̃·Δt [rad] and Δv_k = f̃·Δt [m/s] and the interval's compensation
// from the table's reference motion (table_motion.h):
//
//   φ_k   = Δθ_k + c_k                              rotation vector (c_k: the motion's coning)
//   Δv_b  = [(J(Δθ_k)/h)⁻¹ + ΔM_k] Δv_k              the increment in the body frame at t[k−1]
//
// J/h = (1/h)∫ R(t)ᵀ dt with R(t) the body's rotation since t[k−1]; for a
// constant rate, J(Δθ)/h = I − a [u×] + b [u×]², θ = |Δθ|, u = Δθ/θ,
// a = (1 − cos θ)/θ, b = (θ − sin θ)/θ (Rodrigues' formula integrated with
// the specific force fixed in the navigation frame; MeanBodyRotation below).
// ΔM_k = (J_ref/h)⁻¹ − (J(Δθ_ref)/h)⁻¹ is what the table's actual motion
// within the interval adds to that (zero at a constant rate): the measured
// increment keeps the sensor errors' own effect within the interval (the
// attitude error they build up over it), the reference supplies the shape
// of the motion. Classical two-sample coning and sculling terms (Savage,
// "Strapdown Inertial Navigation Integration Algorithm Design", J. Guidance
// Control Dyn. 21(1–2), 1998) assume instead that the rate changes linearly
// across two samples; on a table whose rate steps they add the errors they
// are meant to remove.
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

// The compensation of one interval (table_motion.h builds it from the reference).
struct IntervalCompensation {
  // ΔM: what the motion's shape adds to the constant-rate velocity map (header).
  Eigen::Matrix3d velocity_map_correction = Eigen::Matrix3d::Zero();
  // Rotation vector of the interval less the integral of the body rate.
  Eigen::Vector3d coning_rad = Eigen::Vector3d::Zero();
};

// Advances `state` over one interval of `dt_s` seconds with the interval's
// increments and compensation.
NavState PropagateStrapdown(const NavState& state, const ImuIncrement& current,
                            const IntervalCompensation& compensation, double dt_s);

// J/h = (1/h)∫₀^h e^{−[ω×]t} dt for a rotation Δθ = ωh at a constant rate: the
// interval mean of a navigation-frame-fixed vector seen in the turning body,
// relative to its value in the frame at the interval's start (see above).
Eigen::Matrix3d MeanBodyRotation(const Eigen::Vector3d& dtheta_rad);

// Transport rate ω_en^n [rad/s] for the velocity and position of `state`.
Eigen::Vector3d TransportRateNed(const NavState& state);

// Gravity vector g^n = [0, 0, γ(φ, h)] [m/s²].
Eigen::Vector3d GravityNed(double latitude_rad, double height_m);

}  // namespace insdiag::engine::nav
