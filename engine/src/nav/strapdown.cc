#include "insdiag/engine/nav/strapdown.h"

#include <cmath>

#include "insdiag/engine/nav/rotation.h"
#include "insdiag/engine/nav/wgs84.h"

namespace insdiag::engine::nav {

Eigen::Vector3d TransportRateNed(const NavState& s) {
  const double rn = wgs84::PrimeVerticalRadiusM(s.latitude_rad) + s.height_m;
  const double rm = wgs84::MeridianRadiusM(s.latitude_rad) + s.height_m;
  return {s.v_n_mps.y() / rn, -s.v_n_mps.x() / rm, -s.v_n_mps.y() * std::tan(s.latitude_rad) / rn};
}

Eigen::Vector3d GravityNed(double latitude_rad, double height_m) {
  return {0.0, 0.0, wgs84::NormalGravityMps2(latitude_rad, height_m)};
}

Eigen::Matrix3d MeanBodyRotation(const Eigen::Vector3d& dtheta) {
  const double theta2 = dtheta.squaredNorm();
  // a/θ and b/θ² of the header, so that J/h = I − (a/θ)[Δθ×] + (b/θ²)[Δθ×]²;
  // below θ = 1e-4 rad the closed forms lose digits and their series serve.
  double a_over_theta, b_over_theta2;
  if (theta2 < 1e-8) {
    a_over_theta = 0.5 - theta2 / 24.0;
    b_over_theta2 = 1.0 / 6.0 - theta2 / 120.0;
  } else {
    const double theta = std::sqrt(theta2);
    a_over_theta = (1.0 - std::cos(theta)) / theta2;
    b_over_theta2 = (theta - std::sin(theta)) / (theta2 * theta);
  }
  const Eigen::Matrix3d K = Skew(dtheta);
  return Eigen::Matrix3d::Identity() - a_over_theta * K + b_over_theta2 * K * K;
}

NavState PropagateStrapdown(const NavState& s, const ImuIncrement& cur, const IntervalCompensation& compensation,
                            double dt) {
  const Eigen::Vector3d phi_b = cur.dtheta_rad + compensation.coning_rad;
  const Eigen::Vector3d dv_b = MeanBodyRotation(cur.dtheta_rad).partialPivLu().solve(cur.dv_mps) +
                               compensation.velocity_map_correction * cur.dv_mps;

  // Earth and transport rates at the start of the interval: on a bench the
  // velocity is ~0 and the rates change by far less than the increments' noise.
  const Eigen::Vector3d w_ie = wgs84::EarthRateNed(s.latitude_rad);
  const Eigen::Vector3d w_en = TransportRateNed(s);
  const Eigen::Vector3d zeta = (w_ie + w_en) * dt;
  const Eigen::Matrix3d C_b_n = s.q_b_n.toRotationMatrix();

  NavState next;
  const Eigen::Vector3d dv_sf_n = (Eigen::Matrix3d::Identity() - 0.5 * Skew(zeta)) * C_b_n * dv_b;
  const Eigen::Vector3d g_n = GravityNed(s.latitude_rad, s.height_m);
  next.v_n_mps = s.v_n_mps + dv_sf_n + (g_n - (2.0 * w_ie + w_en).cross(s.v_n_mps)) * dt;

  const Eigen::Vector3d v_mean = 0.5 * (s.v_n_mps + next.v_n_mps);
  next.height_m = s.height_m - v_mean.z() * dt;
  const double h_mid = 0.5 * (s.height_m + next.height_m);
  const double rm = wgs84::MeridianRadiusM(s.latitude_rad) + h_mid;
  next.latitude_rad = s.latitude_rad + v_mean.x() * dt / rm;
  const double lat_mid = 0.5 * (s.latitude_rad + next.latitude_rad);
  const double rn = wgs84::PrimeVerticalRadiusM(lat_mid) + h_mid;
  next.longitude_rad = s.longitude_rad + v_mean.y() * dt / (rn * std::cos(lat_mid));

  next.q_b_n = (RotationVectorToQuaternion(-zeta) * s.q_b_n * RotationVectorToQuaternion(phi_b)).normalized();
  return next;
}

}  // namespace insdiag::engine::nav
