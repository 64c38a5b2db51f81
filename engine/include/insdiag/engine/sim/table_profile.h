// A two-axis rotary table at a surveyed site and the test profiles it runs.
//
// Geometry: the outer axis is the local vertical (angle α about n-z, down);
// the inner axis is horizontal, the outer gimbal's y axis (angle β). The unit
// is mounted on the inner platform p with a fixed mount rotation C_b^p:
//
//   C_b^n(t) = Rz(α(t)) · Ry(β(t)) · C_b^p
//   ω_nb^b   = C_p^b (Ry(β)ᵀ α̇ e_z + β̇ e_y)                   table rate in body axes
//   ω_ib^b   = ω_nb^b + C_n^b ω_ie^n                            (site fixed: ω_en = 0)
//   f^b      = C_n^b (−g^n)                                     (body at the table centre)
//
// Each axis moves with piecewise-constant angular acceleration (trapezoidal
// rate profiles), so α, β and their rates are exact closed forms at any time.
// Temperature: T(t) = T_amb + ΔT_warm (1 − e^{−t/τ_warm}) + A sin(2π t / P).
#pragma once

#include <absl/status/statusor.h>

#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

namespace insdiag::engine::sim {

struct TableSegment {
  enum class Kind {
    kHold,         // both axes still for duration_s
    kRotateOuter,  // outer axis at rate_rad_s for duration_s (ramps included)
    kRotateInner,  // inner axis at rate_rad_s for duration_s (ramps included)
    kMoveTo,       // slew both axes to the targets at rate_rad_s (duration from the motion)
  };
  Kind kind = Kind::kHold;
  double duration_s = 0.0;
  double rate_rad_s = 0.0;
  double outer_target_rad = 0.0;
  double inner_target_rad = 0.0;
};

struct ThermalProfile {
  double ambient_degc = 0.0;
  double warmup_rise_degc = 0.0;
  double warmup_time_constant_s = 1.0;
  double cycle_amplitude_degc = 0.0;
  double cycle_period_s = 1.0;

  double TemperatureAt(double t_s) const;
};

struct TableProfile {
  std::string name;
  std::string description;
  Eigen::Vector3d mount_rpy_rad = Eigen::Vector3d::Zero();  // C_b^p as roll, pitch, yaw
  double initial_outer_rad = 0.0;
  double initial_inner_rad = 0.0;
  double angular_acceleration_rad_s2 = 0.0;  // of every rate change
  std::vector<TableSegment> segments;
  ThermalProfile thermal;
};

// The built-in profiles (`insdiag simulate --profile NAME`): static, rotations,
// positions, thermal, full. See docs/SIMULATOR.md for what each excites.
std::vector<std::string> BuiltinProfileNames();
absl::StatusOr<TableProfile> BuiltinProfile(std::string_view name);

// The table's motion compiled into phases of constant angular acceleration.
class TableMotion {
 public:
  struct AxisState {
    double angle_rad;
    double rate_rad_s;
  };
  struct Phase {
    double t0_s;
    double outer_angle0, outer_rate0, outer_accel;
    double inner_angle0, inner_rate0, inner_accel;
  };

  static absl::StatusOr<TableMotion> Compile(const TableProfile& profile);

  double DurationS() const { return duration_s_; }
  // Index of the phase that holds time t (the last phase for t past the end).
  size_t PhaseAt(double t_s) const;
  // Start times of all phases after the first, for splitting integration intervals.
  std::vector<double> Breakpoints() const;
  AxisState Outer(double t_s) const;
  AxisState Inner(double t_s) const;
  const Eigen::Matrix3d& C_b_p() const { return C_b_p_; }

  // Body attitude C_b^n and table rate ω_nb^b at time t.
  Eigen::Matrix3d BodyToNed(double t_s) const;
  Eigen::Vector3d TableRateBody(double t_s) const;
  // True while neither axis moves (used to find static segments).
  bool IsStill(double t_s) const;

 private:
  std::vector<Phase> phases_;
  double duration_s_ = 0.0;
  Eigen::Matrix3d C_b_p_ = Eigen::Matrix3d::Identity();
};

}  // namespace insdiag::engine::sim
