#include "insdiag/engine/nav/rotation.h"

#include <cmath>

namespace insdiag::engine::nav {

Eigen::Matrix3d EulerToDcm(const Eigen::Vector3d& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Vector3d DcmToEuler(const Eigen::Matrix3d& C) {
  // C = Rz(y)Ry(p)Rx(r): C(2,0) = −sin p, C(2,1) = sin r cos p, C(2,2) = cos r cos p,
  // C(1,0) = sin y cos p, C(0,0) = cos y cos p.
  const double cos_pitch = std::hypot(C(0, 0), C(1, 0));
  const double pitch = std::atan2(-C(2, 0), cos_pitch);
  // At pitch ±90° only r ∓ y is defined (C(0,1) = ±sin(r ∓ y), C(1,1) = cos(r ∓ y));
  // choose roll 0 so that the angles still reproduce C exactly.
  constexpr double kGimbalLockCosPitch = 1e-9;
  if (cos_pitch < kGimbalLockCosPitch) {
    const double yaw = C(2, 0) < 0.0 ? -std::atan2(C(0, 1), C(1, 1)) : std::atan2(-C(0, 1), C(1, 1));
    return {0.0, pitch, yaw};
  }
  const double roll = std::atan2(C(2, 1), C(2, 2));
  const double yaw = std::atan2(C(1, 0), C(0, 0));
  return {roll, pitch, yaw};
}

Eigen::Quaterniond RotationVectorToQuaternion(const Eigen::Vector3d& phi) {
  const double angle2 = phi.squaredNorm();
  double c;  // cos(|φ|/2)
  double s;  // sin(|φ|/2)/|φ|
  if (angle2 < 1e-10) {
    // Taylor terms up to |φ|⁴: exact to double precision below 1e-5 rad.
    c = 1.0 - angle2 / 8.0 + angle2 * angle2 / 384.0;
    s = 0.5 - angle2 / 48.0 + angle2 * angle2 / 3840.0;
  } else {
    const double angle = std::sqrt(angle2);
    c = std::cos(0.5 * angle);
    s = std::sin(0.5 * angle) / angle;
  }
  return Eigen::Quaterniond(c, s * phi.x(), s * phi.y(), s * phi.z());
}

Eigen::Vector3d QuaternionToRotationVector(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in.w() < 0.0 ? Eigen::Quaterniond(-q_in.coeffs()) : q_in;
  const double vnorm = q.vec().norm();
  if (vnorm < 1e-12) return 2.0 * q.vec();  // small-angle limit, sin(θ/2) ≈ θ/2
  const double angle = 2.0 * std::atan2(vnorm, q.w());
  return q.vec() * (angle / vnorm);
}

}  // namespace insdiag::engine::nav
