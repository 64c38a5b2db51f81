// Rotation helpers for the navigation kernel.
//
// Frames: b = body (x forward, y right, z down), n = local North-East-Down.
// C_b_n rotates body-frame vectors into n: v_n = C_b_n · v_b.
// Euler angles as in the bench-run format: C_b_n = Rz(yaw)·Ry(pitch)·Rx(roll)
// (Titterton & Weston, Strapdown Inertial Navigation Technology, 2nd ed., §3.6.3).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace insdiag::engine::nav {

// [v×]: the matrix with [v×]·w = v × w.
inline Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

// C_b_n from roll, pitch, yaw [rad].
Eigen::Matrix3d EulerToDcm(const Eigen::Vector3d& roll_pitch_yaw_rad);

// Roll, pitch, yaw [rad] of C_b_n; yaw in (−π, π].
Eigen::Vector3d DcmToEuler(const Eigen::Matrix3d& C_b_n);

// Quaternion of the rotation by the rotation vector `phi_rad` (axis · angle).
// Series form near zero so that tiny increments keep full precision
// (q = [cos(|φ|/2), sin(|φ|/2)·φ/|φ|]; Savage, Strapdown Analytics, 2nd ed., ch. 3).
Eigen::Quaterniond RotationVectorToQuaternion(const Eigen::Vector3d& phi_rad);

// Rotation vector of a unit quaternion, angle in [0, π].
Eigen::Vector3d QuaternionToRotationVector(const Eigen::Quaterniond& q);

// The rotation halfway between two unit quaternions along the shorter arc:
// slerp at ½, which is their normalised sum (the sum bisects the arc; Shoemake,
// SIGGRAPH '85) — no trigonometric call, unlike a general slerp.
inline Eigen::Quaterniond Midway(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  const double sign = a.coeffs().dot(b.coeffs()) < 0.0 ? -1.0 : 1.0;
  return Eigen::Quaterniond(a.coeffs() + sign * b.coeffs()).normalized();
}

}  // namespace insdiag::engine::nav
