// The rotary table's motion within each sample interval, from the reference
// attitudes at the sample instants: the compensation the strapdown
// mechanisation applies to the measured increments (strapdown.h).
//
// Why. An increment is an integral over the interval, and turning it into a
// navigation-frame velocity and attitude needs how the body turned *within*
// the interval. Classical algorithms assume it from the increments
// themselves — a constant rate (the rotation compensation), a rate that
// changes linearly across two intervals (the two-sample coning and sculling
// terms). A table's rate that steps within a sample, or a ramp that starts
// inside one, breaks both assumptions, and at 10 Hz the error is a velocity
// jump of g·Δω·h²/8 per rate change (2e-3 m/s for 10 °/s): the filter sees
// outliers and a spurious scale factor. On a rotary table the motion is
// known: the encoders give the attitude at every sample instant.
//
// How. For the interval (t_{k−1}, t_k], the table's rotation relative to the
// local frame is written as the rotation vector r(t) of C_b^n(t_{k−1})ᵀ C_b^n(t)
// (exactly proportional to the angle of whichever axis moves, for any mount).
// Its values at the three instants before the interval and at the three from
// its end on fit a left and a right quadratic in t:
//   * the left one predicts r(t_k): the motion is smooth across t_{k−1}
//     (a constant rate or a ramp that spans the samples); use it;
//   * else the right one predicts r(t_{k−1}): use it;
//   * else the motion changes inside the interval: it follows the left
//     quadratic up to the instant s where the two meet, the right one after
//     (a rate step or the start or end of a ramp inside the sample; exact
//     when each side is a phase of constant angular acceleration).
// Then, with a = C_b^n(t_{k−1})ᵀ ω_in^n the frame's own rate and
// R(t) = Exp(a (t − t_{k−1})) Exp(r(t)) the body's rotation relative to inertial
// space since t_{k−1}, Gauss–Legendre quadrature on each smooth piece gives
//   J/h = (1/h)∫ R(t)ᵀ dt
//   Δθ_ref = ∫ω dt, ω = Exp(r)ᵀ a + J_r(r) ṙ   (J_r the right Jacobian of SO(3))
//   velocity-map correction = (J/h)⁻¹ − (J(Δθ_ref)/h)⁻¹   (zero at a constant rate)
//   coning = Log(R(t_k)) − Δθ_ref
// (Savage, "Strapdown Inertial Navigation Integration Algorithm Design",
// J. Guidance Control Dyn. 21(1–2), 1998: the rotation-vector and velocity
// integrals these replace; Barfoot, State Estimation for Robotics, 2017,
// §7.1.5 for J_r). A still window gives the closed form of the Earth's
// rotation alone.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/nav/strapdown.h"

namespace insdiag::engine::nav {

class ReferenceMotion {
 public:
  // `run` must outlive this object.
  explicit ReferenceMotion(const BenchRun& run);

  // The compensation of the interval (t_{k−1}, t_k], 1 ≤ k < samples; best
  // called for k in order (the reference attitudes of a few samples around
  // k are cached).
  IntervalCompensation Compensation(size_t k);

  // Whether the interval's motion changed inside it (a rate step or a ramp's
  // start or end), and where: for tests and diagnostics.
  struct Shape {
    enum class Kind { kStill, kLeft, kRight, kKink, kChord } kind = Kind::kStill;
    double kink_s = 0.0;  // the instant of the change (kKink only)
  };
  Shape ShapeOf(size_t k) const;

 private:
  const Eigen::Quaterniond& CachedReference(size_t i);

  const BenchRun& run_;
  Eigen::Vector3d frame_rate_n_;
  struct Cached {
    size_t sample = static_cast<size_t>(-1);
    Eigen::Quaterniond q;
  };
  std::array<Cached, 8> cache_;  // ω_in^n of the site (Earth rate; the body is at rest on it)
};

// The compensation of every sample interval of a complete run, computed once
// (in blocks of samples on every core) for the stages that each need it: the
// spike screen's reference measurements and the condensation. A still
// interval holds nothing: 4 bytes a sample, and 96 more for each interval in
// which the table moves.
class RunCompensations {
 public:
  // `run` need not outlive this object.
  explicit RunCompensations(const BenchRun& run);

  // The compensation of interval (t_{k−1}, t_k], 1 ≤ k < samples.
  const IntervalCompensation& At(size_t k) const;

 private:
  std::vector<std::uint32_t> slot_;  // per sample: 0 still, else 1 + its index in moving_
  std::vector<IntervalCompensation> moving_;
  IntervalCompensation still_;
};

}  // namespace insdiag::engine::nav
