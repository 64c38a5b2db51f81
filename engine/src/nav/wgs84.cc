#include "insdiag/engine/nav/wgs84.h"

#include <cmath>

namespace insdiag::engine::wgs84 {

double PrimeVerticalRadiusM(double latitude_rad) {
  const double s = std::sin(latitude_rad);
  return kSemiMajorAxisM / std::sqrt(1.0 - kEccentricitySquared * s * s);
}

double MeridianRadiusM(double latitude_rad) {
  const double s = std::sin(latitude_rad);
  const double d = 1.0 - kEccentricitySquared * s * s;
  return kSemiMajorAxisM * (1.0 - kEccentricitySquared) / (d * std::sqrt(d));
}

double NormalGravityMps2(double latitude_rad, double height_m) {
  const double s2 = std::pow(std::sin(latitude_rad), 2);
  const double gamma0 =
      kGravityEquatorMps2 * (1.0 + kSomiglianaK * s2) / std::sqrt(1.0 - kEccentricitySquared * s2);
  const double a = kSemiMajorAxisM;
  const double height_factor = 1.0 -
                               2.0 / a * (1.0 + kFlattening + kGravityRatioM - 2.0 * kFlattening * s2) * height_m +
                               3.0 * height_m * height_m / (a * a);
  return gamma0 * height_factor;
}

Eigen::Vector3d EarthRateNed(double latitude_rad) {
  return {kEarthRateRadS * std::cos(latitude_rad), 0.0, -kEarthRateRadS * std::sin(latitude_rad)};
}

}  // namespace insdiag::engine::wgs84
