// Analytic coarse alignment of a unit at rest on the Earth: levelling from
// the mean specific force, then gyro-compassing from the mean angular rate
// (Groves, Principles of GNSS, Inertial, and Multisensor Integrated
// Navigation Systems, 2nd ed., §5.6.2, attitude initialization; Titterton & Weston,
// Strapdown Inertial Navigation Technology, 2nd ed., ch. 10).
//
// At rest f^b = C_n^b·[0, 0, −γ] and ω^b = C_n^b·ω_ie^n, with C_b^n =
// Rz(ψ)·Ry(θ)·Rx(φ) (rotation.h). Hence
//   φ = atan2(−f_y, −f_z),   θ = atan2(f_x, √(f_y² + f_z²))
// and, with ω^l = Ry(θ)·Rx(φ)·ω^b the rate in the levelled frame, whose
// horizontal part is Ω cos L·[cos ψ, −sin ψ]:
//   ψ = atan2(−ω^l_y, ω^l_x)
// A gyro bias b across the levelled x axis turns the heading by about
// b / (Ω cos L); a tilt error δ turns it by about δ·tan L.
#pragma once

#include <Eigen/Core>
#include <optional>

namespace insdiag::engine::nav {

// Roll, pitch and yaw [rad] of a unit at rest from its mean specific force
// [m/s²] and mean angular rate [rad/s], both in body axes. With
// `heading_rad` given, the yaw is that heading and the rates are not used.
Eigen::Vector3d CoarseAlignment(const Eigen::Vector3d& mean_specific_force_mps2,
                                const Eigen::Vector3d& mean_rate_rad_s,
                                std::optional<double> heading_rad = std::nullopt);

}  // namespace insdiag::engine::nav
