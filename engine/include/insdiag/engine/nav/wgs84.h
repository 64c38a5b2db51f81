// WGS-84 Earth model: ellipsoid, Earth rotation rate, normal gravity.
//
// Constants: NIMA TR8350.2, "Department of Defense World Geodetic System 1984",
// 3rd ed. (2000), Tables 3.1 and 3.3.
//
//   R_N(φ) = a / √(1 − e² sin²φ)                      prime-vertical radius [m]
//   R_M(φ) = a (1 − e²) / (1 − e² sin²φ)^{3/2}        meridian radius [m]
//   γ0(φ)  = γe (1 + k sin²φ) / √(1 − e² sin²φ)       Somigliana normal gravity (TR8350.2 eq. 4-1)
//   γ(φ,h) = γ0 [1 − 2/a (1 + f + m − 2 f sin²φ) h + 3 h²/a²]   (TR8350.2 eq. 4-3)
//   ω_ie^n = Ω [cos φ, 0, −sin φ]                     Earth rate in North-East-Down [rad/s]
#pragma once

#include <Eigen/Core>

namespace insdiag::engine::wgs84 {

inline constexpr double kSemiMajorAxisM = 6378137.0;
inline constexpr double kFlattening = 1.0 / 298.257223563;
inline constexpr double kEccentricitySquared = kFlattening * (2.0 - kFlattening);
inline constexpr double kEarthRateRadS = 7.292115e-5;
inline constexpr double kGravityEquatorMps2 = 9.7803253359;
inline constexpr double kSomiglianaK = 0.00193185265241;
// m = ω² a² b / GM (TR8350.2 Table 3.3).
inline constexpr double kGravityRatioM = 0.00344978650684;

double PrimeVerticalRadiusM(double latitude_rad);
double MeridianRadiusM(double latitude_rad);

// Magnitude of normal gravity at geodetic latitude and ellipsoidal height [m/s²].
double NormalGravityMps2(double latitude_rad, double height_m);

// Earth rotation rate resolved in local North-East-Down [rad/s].
Eigen::Vector3d EarthRateNed(double latitude_rad);

}  // namespace insdiag::engine::wgs84
