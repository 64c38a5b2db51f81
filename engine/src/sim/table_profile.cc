#include "insdiag/engine/sim/table_profile.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "insdiag/engine/nav/rotation.h"

namespace insdiag::engine::sim {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// Builds phases one axis motion at a time; both axes' angles are carried.
class PhaseBuilder {
 public:
  PhaseBuilder(double outer0, double inner0, double accel) : outer_(outer0), inner_(inner0), accel_(accel) {}

  void Hold(double duration) { Push(duration, 0.0, 0.0, 0.0, 0.0); }

  // Trapezoidal rate profile on one axis: ramp to `rate`, cruise, ramp to 0.
  absl::Status Rotate(bool outer, double rate, double duration) {
    const double ramp = std::abs(rate) / accel_;
    if (duration < 2.0 * ramp) {
      return absl::InvalidArgumentError("a rotation segment is shorter than its acceleration ramps");
    }
    const double a = std::copysign(accel_, rate);
    PushAxis(outer, ramp, 0.0, a);
    PushAxis(outer, duration - 2.0 * ramp, rate, 0.0);
    PushAxis(outer, ramp, rate, -a);
    return absl::OkStatus();
  }

  // Slews one axis by `distance` with peak rate `max_rate` (triangular when short).
  void Slew(bool outer, double distance, double max_rate) {
    if (distance == 0.0) return;
    const double sign = distance > 0 ? 1.0 : -1.0;
    const double d = std::abs(distance);
    double peak = max_rate;
    double cruise = 0.0;
    if (d >= max_rate * max_rate / accel_) {
      cruise = (d - max_rate * max_rate / accel_) / max_rate;
    } else {
      peak = std::sqrt(d * accel_);
    }
    const double ramp = peak / accel_;
    PushAxis(outer, ramp, 0.0, sign * accel_);
    if (cruise > 0.0) PushAxis(outer, cruise, sign * peak, 0.0);
    PushAxis(outer, ramp, sign * peak, -sign * accel_);
  }

  double outer() const { return outer_; }
  double inner() const { return inner_; }
  std::vector<TableMotion::Phase> Take(double* duration) {
    *duration = t_;
    return std::move(phases_);
  }

 private:
  void PushAxis(bool outer, double duration, double rate0, double accel) {
    if (outer) {
      Push(duration, rate0, accel, 0.0, 0.0);
    } else {
      Push(duration, 0.0, 0.0, rate0, accel);
    }
  }
  void Push(double duration, double outer_rate0, double outer_accel, double inner_rate0, double inner_accel) {
    if (duration <= 0.0) return;
    phases_.push_back({t_, outer_, outer_rate0, outer_accel, inner_, inner_rate0, inner_accel});
    outer_ += outer_rate0 * duration + 0.5 * outer_accel * duration * duration;
    inner_ += inner_rate0 * duration + 0.5 * inner_accel * duration * duration;
    t_ += duration;
  }

  double outer_, inner_, accel_;
  double t_ = 0.0;
  std::vector<TableMotion::Phase> phases_;
};

TableSegment Hold(double s) { return {TableSegment::Kind::kHold, s, 0, 0, 0}; }
TableSegment MoveTo(double outer_deg, double inner_deg, double rate_deg_s) {
  return {TableSegment::Kind::kMoveTo, 0, rate_deg_s * kDeg, outer_deg * kDeg, inner_deg * kDeg};
}
// `turns` full turns at `rate_deg_s`, including the ramps at `accel_deg_s2`.
TableSegment Turns(TableSegment::Kind kind, double turns, double rate_deg_s, double accel_deg_s2) {
  const double ramp = std::abs(rate_deg_s) / accel_deg_s2;
  const double duration = turns * 360.0 / std::abs(rate_deg_s) + ramp;
  return {kind, duration, rate_deg_s * kDeg, 0, 0};
}

// Table rates and accelerations typical of a navigation-grade test table.
constexpr double kRateDegS = 10.0;
constexpr double kAccelDegS2 = 10.0;

void AppendSpins(std::vector<TableSegment>& s, TableSegment::Kind kind, double turns, double hold_s) {
  s.push_back(Turns(kind, turns, kRateDegS, kAccelDegS2));
  s.push_back(Hold(hold_s));
  s.push_back(Turns(kind, turns, -kRateDegS, kAccelDegS2));
  s.push_back(Hold(hold_s));
}

TableProfile Base(std::string name, std::string description, double mount_yaw_deg) {
  TableProfile p;
  p.name = std::move(name);
  p.description = std::move(description);
  p.mount_rpy_rad = {0.0, 0.0, mount_yaw_deg * kDeg};
  p.angular_acceleration_rad_s2 = kAccelDegS2 * kDeg;
  p.thermal.ambient_degc = 25.0;
  return p;
}

TableProfile StaticProfile() {
  TableProfile p = Base("static", "level and still for one hour at constant temperature", 0.0);
  p.segments = {Hold(3600.0)};
  return p;
}

TableProfile RotationsProfile() {
  TableProfile p = Base("rotations",
                        "one hour: constant-rate turns about body z, y and x in both directions, "
                        "static holds between, constant temperature",
                        0.0);
  auto& s = p.segments;
  s.push_back(Hold(300.0));
  for (int cycle = 0; cycle < 2; ++cycle) {
    AppendSpins(s, TableSegment::Kind::kRotateOuter, 5, 90.0);  // about body z
    AppendSpins(s, TableSegment::Kind::kRotateInner, 5, 90.0);  // about body y (the inner axis)
    s.push_back(MoveTo(0.0, 90.0, kRateDegS));                   // body x vertical
    s.push_back(Hold(60.0));
    AppendSpins(s, TableSegment::Kind::kRotateOuter, 5, 90.0);  // about body x
    s.push_back(MoveTo(0.0, 0.0, kRateDegS));
    s.push_back(Hold(60.0));
  }
  s.push_back(Hold(150.0));
  return p;
}

// Mounting the unit at 45° yaw on the inner platform puts gravity on every
// accelerometer axis over the tilts (a single mount on a two-axis table
// cannot stand each body axis vertical in turn).
constexpr double kSkewMountYawDeg = 45.0;

void AppendPositions(std::vector<TableSegment>& s, std::initializer_list<double> inner_deg,
                     std::initializer_list<double> outer_deg, double hold_s) {
  for (double inner : inner_deg) {
    for (double outer : outer_deg) {
      s.push_back(MoveTo(outer, inner, kRateDegS));
      s.push_back(Hold(hold_s));
    }
  }
}

TableProfile PositionsProfile() {
  TableProfile p = Base("positions",
                        "one hour of static tilts: 16 positions (inner 0/90/180/270°, outer 0/90/180/270°), "
                        "unit mounted at 45° yaw so every accelerometer sees gravity",
                        kSkewMountYawDeg);
  p.segments.push_back(Hold(200.0));
  AppendPositions(p.segments, {0, 90, 180, 270}, {0, 90, 180, 270}, 200.0);
  p.segments.push_back(MoveTo(0, 0, kRateDegS));
  p.segments.push_back(Hold(60.0));
  return p;
}

TableProfile ThermalCyclesProfile() {
  TableProfile p = Base("thermal", "two hours level and still through a warm-up and thermal cycles", 0.0);
  p.segments = {Hold(7200.0)};
  p.thermal.warmup_rise_degc = 10.0;
  p.thermal.warmup_time_constant_s = 1200.0;
  p.thermal.cycle_amplitude_degc = 5.0;
  p.thermal.cycle_period_s = 1800.0;
  return p;
}

TableProfile FullProfile() {
  TableProfile p = Base("full",
                        "two hours: tilts, turns about three independent body directions in both senses, "
                        "warm-up and thermal cycles; unit mounted at 45° yaw — excites every constant catalogue effect "
                        "and the second-order drifts (a bias random walk needs the hours of `drift`)",
                        kSkewMountYawDeg);
  auto& s = p.segments;
  s.push_back(Hold(300.0));
  AppendPositions(s, {0, 90, 180, 270}, {0, 180}, 150.0);
  s.push_back(MoveTo(0, 0, kRateDegS));
  s.push_back(Hold(60.0));
  for (double inner : {0.0, 90.0, 180.0}) {
    s.push_back(MoveTo(0, inner, kRateDegS));
    s.push_back(Hold(60.0));
    AppendSpins(s, TableSegment::Kind::kRotateOuter, 4, 60.0);
  }
  s.push_back(MoveTo(0, 0, kRateDegS));
  AppendSpins(s, TableSegment::Kind::kRotateInner, 4, 60.0);
  s.push_back(MoveTo(90, 0, kRateDegS));
  AppendSpins(s, TableSegment::Kind::kRotateInner, 4, 60.0);
  AppendPositions(s, {45, 135, 225, 315}, {90, 270}, 150.0);
  s.push_back(MoveTo(0, 0, kRateDegS));
  s.push_back(Hold(600.0));
  p.thermal.warmup_rise_degc = 8.0;
  p.thermal.warmup_time_constant_s = 900.0;
  p.thermal.cycle_amplitude_degc = 4.0;
  p.thermal.cycle_period_s = 1800.0;
  return p;
}

// A drift test: a drift's σ and τ are told apart only over many correlation
// times (the relative error of a variance estimated from a record of length
// T is about √(2τ/T) for a first-order Gauss–Markov process; Papoulis,
// Probability, Random Variables and Stochastic Processes, §11), so the unit
// holds still for hours — in eight tilted positions, one hour each, so that
// every gyro and accelerometer axis is seen against gravity and Earth rate.
TableProfile DriftProfile() {
  TableProfile p = Base("drift",
                        "eight hours of static holds in eight tilted positions (inner 0/90/180/270°, outer 0/180°), "
                        "one hour each, constant temperature, unit mounted at 45° yaw: a drift test",
                        kSkewMountYawDeg);
  p.segments.push_back(Hold(60.0));
  AppendPositions(p.segments, {0, 90, 180, 270}, {0, 180}, 3600.0);
  return p;
}

}  // namespace

double ThermalProfile::TemperatureAt(double t) const {
  return ambient_degc + warmup_rise_degc * (1.0 - std::exp(-t / warmup_time_constant_s)) +
         cycle_amplitude_degc * std::sin(2.0 * std::numbers::pi * t / cycle_period_s);
}

std::vector<std::string> BuiltinProfileNames() { return {"static", "rotations", "positions", "thermal", "full", "drift"}; }

absl::StatusOr<TableProfile> BuiltinProfile(std::string_view name) {
  if (name == "static") return StaticProfile();
  if (name == "rotations") return RotationsProfile();
  if (name == "positions") return PositionsProfile();
  if (name == "thermal") return ThermalCyclesProfile();
  if (name == "full") return FullProfile();
  if (name == "drift") return DriftProfile();
  std::string names;
  for (const auto& n : BuiltinProfileNames()) names += (names.empty() ? "" : ", ") + n;
  return absl::InvalidArgumentError("unknown profile '" + std::string(name) + "'; built-in profiles: " + names);
}

absl::StatusOr<TableMotion> TableMotion::Compile(const TableProfile& profile) {
  if (!(profile.angular_acceleration_rad_s2 > 0.0)) {
    return absl::InvalidArgumentError("the table's angular acceleration must be positive");
  }
  PhaseBuilder b(profile.initial_outer_rad, profile.initial_inner_rad, profile.angular_acceleration_rad_s2);
  for (const TableSegment& seg : profile.segments) {
    switch (seg.kind) {
      case TableSegment::Kind::kHold:
        b.Hold(seg.duration_s);
        break;
      case TableSegment::Kind::kRotateOuter:
      case TableSegment::Kind::kRotateInner:
        if (auto st = b.Rotate(seg.kind == TableSegment::Kind::kRotateOuter, seg.rate_rad_s, seg.duration_s);
            !st.ok()) {
          return st;
        }
        break;
      case TableSegment::Kind::kMoveTo:
        if (!(seg.rate_rad_s > 0.0)) return absl::InvalidArgumentError("a move needs a positive rate");
        b.Slew(true, seg.outer_target_rad - b.outer(), seg.rate_rad_s);
        b.Slew(false, seg.inner_target_rad - b.inner(), seg.rate_rad_s);
        break;
    }
  }
  TableMotion m;
  m.phases_ = b.Take(&m.duration_s_);
  if (m.phases_.empty()) return absl::InvalidArgumentError("the profile has no motion or holds");
  m.C_b_p_ = nav::EulerToDcm(profile.mount_rpy_rad);
  return m;
}

size_t TableMotion::PhaseAt(double t) const {
  auto it = std::upper_bound(phases_.begin(), phases_.end(), t,
                             [](double time, const Phase& p) { return time < p.t0_s; });
  return it == phases_.begin() ? 0 : static_cast<size_t>(it - phases_.begin()) - 1;
}

std::vector<double> TableMotion::Breakpoints() const {
  std::vector<double> b;
  for (size_t i = 1; i < phases_.size(); ++i) b.push_back(phases_[i].t0_s);
  return b;
}

TableMotion::AxisState TableMotion::Outer(double t) const {
  const Phase& p = phases_[PhaseAt(t)];
  const double dt = t - p.t0_s;
  return {p.outer_angle0 + p.outer_rate0 * dt + 0.5 * p.outer_accel * dt * dt, p.outer_rate0 + p.outer_accel * dt};
}

TableMotion::AxisState TableMotion::Inner(double t) const {
  const Phase& p = phases_[PhaseAt(t)];
  const double dt = t - p.t0_s;
  return {p.inner_angle0 + p.inner_rate0 * dt + 0.5 * p.inner_accel * dt * dt, p.inner_rate0 + p.inner_accel * dt};
}

Eigen::Matrix3d TableMotion::BodyToNed(double t) const {
  return (Eigen::AngleAxisd(Outer(t).angle_rad, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(Inner(t).angle_rad, Eigen::Vector3d::UnitY()))
             .toRotationMatrix() *
         C_b_p_;
}

Eigen::Vector3d TableMotion::TableRateBody(double t) const {
  const AxisState outer = Outer(t);
  const AxisState inner = Inner(t);
  const Eigen::Matrix3d Ry = Eigen::AngleAxisd(inner.angle_rad, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Vector3d w_np_p = Ry.transpose() * Eigen::Vector3d::UnitZ() * outer.rate_rad_s +
                                 Eigen::Vector3d::UnitY() * inner.rate_rad_s;
  return C_b_p_.transpose() * w_np_p;
}

bool TableMotion::IsStill(double t) const {
  const Phase& p = phases_[PhaseAt(t)];
  return p.outer_rate0 == 0.0 && p.outer_accel == 0.0 && p.inner_rate0 == 0.0 && p.inner_accel == 0.0;
}

}  // namespace insdiag::engine::sim
