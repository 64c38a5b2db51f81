#include "insdiag/engine/nav/coarse_alignment.h"

#include <cmath>

namespace insdiag::engine::nav {

Eigen::Vector3d CoarseAlignment(const Eigen::Vector3d& f, const Eigen::Vector3d& w,
                                std::optional<double> heading_rad) {
  const double roll = std::atan2(-f.y(), -f.z());
  const double pitch = std::atan2(f.x(), std::hypot(f.y(), f.z()));
  if (heading_rad.has_value()) return {roll, pitch, *heading_rad};
  const double sr = std::sin(roll), cr = std::cos(roll), sp = std::sin(pitch), cp = std::cos(pitch);
  const double levelled_x = cp * w.x() + sp * sr * w.y() + sp * cr * w.z();
  const double levelled_y = cr * w.y() - sr * w.z();
  return {roll, pitch, std::atan2(-levelled_y, levelled_x)};
}

}  // namespace insdiag::engine::nav
