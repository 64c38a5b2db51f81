#include "insdiag/engine/nav/table_motion.h"

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

#include "insdiag/engine/nav/rotation.h"
#include "insdiag/engine/nav/strapdown.h"
#include "insdiag/engine/nav/wgs84.h"
#include "insdiag/engine/numerics/golden_section.h"
#include "insdiag/engine/numerics/parallel_map.h"

namespace insdiag::engine::nav {

namespace {

// r(t) = c[0] + c[1] u + c[2] u² + c[3] u³, u = t − t_{k−1}, on [from, to].
struct Piece {
  std::array<Eigen::Vector3d, 4> c;
  double from = 0.0, to = 0.0;

  Eigen::Vector3d At(double u) const { return c[0] + u * (c[1] + u * (c[2] + u * c[3])); }
  Eigen::Vector3d RateAt(double u) const { return c[1] + u * (2.0 * c[2] + 3.0 * u * c[3]); }
};

// The motion of an interval: one smooth piece, or two meeting at a change.
struct Pieces {
  std::array<Piece, 2> piece;
  int count = 0;

  void clear() { count = 0; }
  void push_back(const Piece& p) { piece[static_cast<size_t>(count++)] = p; }
  const Piece& back() const { return piece[static_cast<size_t>(count - 1)]; }
  const Piece* begin() const { return piece.data(); }
  const Piece* end() const { return piece.data() + count; }
};

// A rotation below this angle counts as none: far under a table encoder's
// resolution (≈ 5e-6 rad).
constexpr double kStillRad = 1e-12;

// How far a side's quadratic may miss the interval's other end and still
// describe it: rounding of the reference angles, relative to the interval's
// own rotation. A rate step misses by ~|Δω| h, a ramp's start by ~α h²:
// orders of magnitude above it at any bench rate.
double Tolerance(double interval_rotation_rad) { return 1e-10 + 1e-6 * interval_rotation_rad; }

// The polynomial through the points (u_i, r_i) (three: a quadratic, four: a
// cubic), by Newton's divided differences expanded into powers of u.
Piece Interpolate(const double* u, const Eigen::Vector3d* r, int count) {
  std::array<Eigen::Vector3d, 4> d;
  for (int i = 0; i < count; ++i) d[static_cast<size_t>(i)] = r[i];
  for (int level = 1; level < count; ++level) {
    for (int i = count - 1; i >= level; --i) {
      d[static_cast<size_t>(i)] = (d[static_cast<size_t>(i)] - d[static_cast<size_t>(i - 1)]) / (u[i] - u[i - level]);
    }
  }
  // Horner on the Newton form: P = d0 + (u − u0)(d1 + (u − u1)(d2 + (u − u2) d3)).
  Piece piece;
  for (auto& c : piece.c) c.setZero();
  for (int i = count - 1; i >= 0; --i) {
    // piece ← piece·(u − u_i) + d_i
    for (int p = 3; p >= 1; --p) piece.c[static_cast<size_t>(p)] = piece.c[static_cast<size_t>(p - 1)] - u[i] * piece.c[static_cast<size_t>(p)];
    piece.c[0] = d[static_cast<size_t>(i)] - u[i] * piece.c[0];
  }
  return piece;
}

// Four-point Gauss–Legendre on [−1, 1] (Abramowitz & Stegun 25.4.30): exact
// for polynomials up to degree 7; the integrands here are smooth on each piece.
constexpr std::array<double, 4> kNodes = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                                          0.8611363115940526};
constexpr std::array<double, 4> kWeights = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                                            0.3478548451374538};

Eigen::Quaterniond ReferenceAt(const BenchRun& run, size_t k) {
  return Eigen::Quaterniond(EulerToDcm(run.samples[k].ref_rpy_rad));
}

using Shape = ReferenceMotion::Shape;

// The motion of interval k as one or two smooth pieces (header);
// `reference(i)` is the reference attitude of sample i.
template <typename Reference>
Shape Reconstruct(const BenchRun& run_, size_t k, const Reference& reference, Pieces& pieces) {
  pieces.clear();
  const size_t n = run_.samples.size();
  const double t0 = run_.samples[k - 1].t_s;
  const double h = run_.samples[k].t_s - t0;
  const Eigen::Quaterniond base_inverse = reference(k - 1).conjugate();
  // A table at rest over the whole window: the same reference attitude throughout.
  {
    const Eigen::Quaterniond base = reference(k - 1);
    bool still = true;
    for (size_t i = k >= 3 ? k - 3 : 0; still && i < std::min(n, k + 3); ++i) {
      still = reference(i).coeffs() == base.coeffs();
    }
    if (still) {
      Piece p;
      for (auto& c : p.c) c.setZero();
      p.to = h;
      pieces.push_back(p);
      return Shape{Shape::Kind::kStill, 0.0};
    }
  }
  // r at t_{k−3} … t_{k+2}, where the run has them (index i ↔ sample k − 3 + i).
  std::array<Eigen::Vector3d, 6> r;
  std::array<double, 6> u;
  std::array<bool, 6> have;
  double largest = 0.0;
  for (int i = 0; i < 6; ++i) {
    const long s = static_cast<long>(k) - 3 + i;
    have[static_cast<size_t>(i)] = s >= 0 && s < static_cast<long>(n);
    if (!have[static_cast<size_t>(i)]) continue;
    const auto si = static_cast<size_t>(s);
    u[static_cast<size_t>(i)] = run_.samples[si].t_s - t0;
    r[static_cast<size_t>(i)] = s == static_cast<long>(k) - 1 ? Eigen::Vector3d::Zero()
                                                              : QuaternionToRotationVector(base_inverse * reference(si));
    largest = std::max(largest, r[static_cast<size_t>(i)].norm());
  }
  auto chord = [&](Shape::Kind kind) {
    Piece p;
    for (auto& c : p.c) c.setZero();
    p.c[1] = r[3] / h;
    p.from = 0.0;
    p.to = h;
    pieces.push_back(p);
    return Shape{kind, 0.0};
  };
  if (largest < kStillRad) return chord(Shape::Kind::kStill);

  const double tol = Tolerance(r[3].norm());
  std::optional<Piece> left, right;
  if (have[0]) left = Interpolate(&u[0], &r[0], 3);   // t_{k−3}, t_{k−2}, t_{k−1}
  if (have[5]) right = Interpolate(&u[3], &r[3], 3);  // t_k, t_{k+1}, t_{k+2}
  const double left_miss = left ? (left->At(h) - r[3]).norm() : std::numeric_limits<double>::infinity();
  const double right_miss = right ? right->At(0.0).norm() : std::numeric_limits<double>::infinity();
  auto whole = [&](Piece p, Shape::Kind kind) {
    p.from = 0.0;
    p.to = h;
    pieces.push_back(p);
    return Shape{kind, 0.0};
  };
  if (left_miss <= tol && left_miss <= right_miss) return whole(*left, Shape::Kind::kLeft);
  if (right_miss <= tol) return whole(*right, Shape::Kind::kRight);
  if (left && right) {
    // Where the two sides meet: the minimum of |L(s) − R(s)|² over the
    // interval, a quartic — a grid, then golden-section refinement.
    auto gap = [&](double s) { return (left->At(s) - right->At(s)).squaredNorm(); };
    constexpr int kGrid = 32;
    int best = 0;
    double best_gap = gap(0.0);
    for (int i = 1; i <= kGrid; ++i) {
      const double g = gap(h * i / kGrid);
      if (g < best_gap) {
        best = i;
        best_gap = g;
      }
    }
    const double lo = h * std::max(0, best - 1) / kGrid, hi = h * std::min(kGrid, best + 1) / kGrid;
    // The bracket's share of the interval: far below the reference's resolution.
    constexpr double kBracketShare = 1e-13;
    const double s =
        numerics::GoldenSectionMaximum(lo, hi, h * best / kGrid, -best_gap, kBracketShare * h,
                                       [&](double x) { return -gap(x); })
            .second;
    // A true change inside the interval: the sides meet to within the
    // reference's resolution, far closer than either misses the other end.
    if (std::sqrt(gap(s)) <= 1e-9 + 1e-4 * r[3].norm()) {
      Piece a = *left, b = *right;
      a.from = 0.0;
      a.to = s;
      b.from = s;
      b.to = h;
      if (s > 0.0) pieces.push_back(a);
      if (s < h) pieces.push_back(b);
      return Shape{Shape::Kind::kKink, t0 + s};
    }
  }
  // Smooth but not a quadratic on either side (two axes turning together):
  // the cubic through the four instants around the interval.
  if (have[1] && have[4]) return whole(Interpolate(&u[1], &r[1], 4), Shape::Kind::kChord);
  return chord(Shape::Kind::kChord);
}

}  // namespace

ReferenceMotion::ReferenceMotion(const BenchRun& run)
    : run_(run), frame_rate_n_(wgs84::EarthRateNed(run.metadata.site.latitude_rad)) {}

ReferenceMotion::Shape ReferenceMotion::ShapeOf(size_t k) const {
  Pieces pieces;
  return Reconstruct(run_, k, [&](size_t i) { return ReferenceAt(run_, i); }, pieces);
}

const Eigen::Quaterniond& ReferenceMotion::CachedReference(size_t i) {
  Cached& slot = cache_[i % cache_.size()];
  if (slot.sample != i) slot = {i, ReferenceAt(run_, i)};
  return slot.q;
}

IntervalCompensation ReferenceMotion::Compensation(size_t k) {
  Pieces pieces;
  const Shape shape = Reconstruct(run_, k, [&](size_t i) { return CachedReference(i); }, pieces);
  const double h = run_.samples[k].t_s - run_.samples[k - 1].t_s;
  IntervalCompensation out;
  // The Earth's rotation alone is a constant rate in the body: nothing to
  // add. A table turning at a constant rate is not quite: with the Earth's
  // rate the body's axis of rotation wanders (terms in Ω·ω·h² a sample) and,
  // on the same side every sample of a turn, they add up.
  if (shape.kind == Shape::Kind::kStill) return out;
  const Eigen::Vector3d a = CachedReference(k - 1).conjugate() * frame_rate_n_;  // ω_in in the start body frame
  Eigen::Matrix3d J = Eigen::Matrix3d::Zero();
  Eigen::Vector3d integral = Eigen::Vector3d::Zero();
  for (const Piece& p : pieces) {
    const double half = 0.5 * (p.to - p.from), mid = 0.5 * (p.to + p.from);
    for (size_t i = 0; i < kNodes.size(); ++i) {
      const double u = mid + half * kNodes[i];
      const double w = half * kWeights[i];
      const Eigen::Vector3d r = p.At(u);
      const Eigen::Matrix3d R_nb = RotationVectorToQuaternion(r).toRotationMatrix();
      const Eigen::Matrix3d R_ib = RotationVectorToQuaternion(a * u).toRotationMatrix() * R_nb;
      J += w * R_ib.transpose();
      // J_r(r) is the same series as the mean body rotation of r (strapdown.h).
      integral += w * (R_nb.transpose() * a + MeanBodyRotation(r) * p.RateAt(u));
    }
  }
  out.velocity_map_correction = (J / h).inverse() - MeanBodyRotation(integral).inverse();
  const Eigen::Vector3d r_end = pieces.back().At(h);
  const Eigen::Vector3d phi = QuaternionToRotationVector(RotationVectorToQuaternion(a * h) * RotationVectorToQuaternion(r_end));
  out.coning_rad = phi - integral;
  return out;
}

RunCompensations::RunCompensations(const BenchRun& run) : slot_(run.samples.size(), 0) {
  const size_t n = run.samples.size();
  if (n < 2) return;
  // Each block's moving intervals, then numbered in sample order: the same
  // whatever the thread count.
  const auto blocks = static_cast<size_t>(numerics::WorkerThreads());
  auto parts = numerics::ParallelMap(blocks, [&](size_t b) {
    const size_t begin = std::max<size_t>(1, n * b / blocks);
    const size_t end = n * (b + 1) / blocks;
    std::vector<std::pair<size_t, IntervalCompensation>> moving;
    ReferenceMotion motion(run);
    for (size_t k = begin; k < end; ++k) {
      IntervalCompensation c = motion.Compensation(k);
      if (c.coning_rad.isZero(0.0) && c.velocity_map_correction.isZero(0.0)) continue;
      moving.emplace_back(k, std::move(c));
    }
    return moving;
  });
  for (auto& part : parts) {
    for (auto& [k, c] : part) {
      moving_.push_back(std::move(c));
      slot_[k] = static_cast<std::uint32_t>(moving_.size());
    }
  }
}

const IntervalCompensation& RunCompensations::At(size_t k) const {
  const std::uint32_t slot = slot_[k];
  return slot == 0 ? still_ : moving_[slot - 1];
}

}  // namespace insdiag::engine::nav
