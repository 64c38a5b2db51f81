#include "insdiag/engine/filter/observation.h"

#include <cmath>

#include <Eigen/Geometry>

#include "insdiag/engine/nav/rotation.h"
#include "insdiag/engine/nav/wgs84.h"

namespace insdiag::engine {

std::array<ObservationRow, kChannelCount> ObservationRows(const StateLayout& layout) {
  const int pos = layout.position();
  const int vel = layout.velocity();
  const int att = layout.attitude();
  return {{{pos + 0, 1.0},
           {pos + 1, 1.0},
           {pos + 2, -1.0},
           {vel + 0, 1.0},
           {vel + 1, 1.0},
           {vel + 2, 1.0},
           {att + 0, 1.0},
           {att + 1, 1.0},
           {att + 2, 1.0}}};
}

std::array<double, kChannelCount> Observe(const nav::NavState& ins, const Site& site,
                                          const Eigen::Matrix3d& C_ref) {
  const double rm = wgs84::MeridianRadiusM(site.latitude_rad) + site.height_m;
  const double rn = wgs84::PrimeVerticalRadiusM(site.latitude_rad) + site.height_m;
  // ψ = Log(C_ref C̃ᵀ) (header).
  const Eigen::Vector3d psi =
      nav::QuaternionToRotationVector(Eigen::Quaterniond(C_ref) * ins.q_b_n.conjugate());
  return {(ins.latitude_rad - site.latitude_rad) * rm,
          (ins.longitude_rad - site.longitude_rad) * rn * std::cos(site.latitude_rad),
          ins.height_m - site.height_m,
          ins.v_n_mps.x(),
          ins.v_n_mps.y(),
          ins.v_n_mps.z(),
          psi.x(),
          psi.y(),
          psi.z()};
}

}  // namespace insdiag::engine
