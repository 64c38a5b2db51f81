// Bench simulator: a unit with a known error model on a two-axis rotary table,
// producing a bench run in the format's conventions and keeping the truth.
//
// Sample k covers (t[k−1], t[k]] with t[k] = k/rate. Its gyro and accelerometer
// values are interval means of the true body rate and specific force
// (3-point Gauss–Legendre quadrature on every piece between motion
// breakpoints: exact to far below the sensors' noise), plus the sensor errors:
//   base Gauss–Markov drift, exact discretisation (seed eq. 5):
//     b[k] = φ b[k−1] + σ √(1 − φ²) ξ,  φ = e^{−Δt/τ},  b[0] ~ N(0, σ²)
//   white noise, interval mean: N(0, N²/Δt) (N = ARW or VRW)
//   every catalogue effect (effect_catalogue.h, error_model.h)
//   faults: bias steps and one-sample spikes
//   quantisation: increments rounded to the quantum q = √12·Q with the
//     remainder carried (IEEE Std 952, Annex C: Q = q/√12)
#pragma once

#include <absl/status/statusor.h>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/model/error_model.h"
#include "insdiag/engine/sim/table_profile.h"

namespace insdiag::engine::sim {

// A catalogue term hidden in the simulated unit, with its true values.
struct TrueEffect {
  EffectTerm term;
  // Constant families: the parameter(s) (yaw harmonics: sin, cos amplitudes).
  std::array<double, 2> value = {0.0, 0.0};
  // bias_rw: K [unit/√s]; bias_second_order: σ [unit], α [1/s], β [rad/s].
  double random_walk_density = 0.0;
  double second_order_sigma = 0.0;
  double second_order_alpha_per_s = 0.0;
  double second_order_beta_rad_s = 0.0;
  // Fault families (bias steps and ramps): the onset [s of run time].
  double onset_s = 0.0;
  // Warm-ups: the start value is value[0], settling with this time constant [s].
  double time_constant_s = 0.0;
};

// The comma-separated finite numbers of `text` ("1.5,-2,3e-3"; empty: none).
// `what` names the input in the error: "<what>: 'x' is not a number".
absl::StatusOr<std::vector<double>> ParseNumberList(std::string_view text, std::string_view what);

// Parses `NAME=VALUE[,VALUE…]` (insdiag simulate --effect): NAME is a term
// ("gyro_scale_factor.z") or a family (every axis gets the value). Values:
// constant families one value (yaw harmonics: sin[,cos]); bias_rw K;
// bias_second_order σ,τ_s,period_s (α = 1/τ, β = 2π/period); warm_up
// START,TAU_S (the bias at the first sample and its time constant); faults
// VALUE@ONSET_S (gyro_bias_ramp.x=1e-9@1500).
absl::StatusOr<std::vector<TrueEffect>> ParseTrueEffect(std::string_view spec);

struct BiasStep {
  Sensor sensor = Sensor::kGyro;
  int axis = 0;
  double time_s = 0.0;
  double size = 0.0;  // rad/s or m/s²
};

struct Spike {
  Sensor sensor = Sensor::kGyro;
  int axis = 0;
  double time_s = 0.0;  // the sample whose interval holds this time
  double size = 0.0;
};

struct SimulatedUnit {
  std::string serial;
  std::string type;
  SensorTriadModel gyro;  // true base model, rad/s
  SensorTriadModel acc;   // m/s²
  std::vector<TrueEffect> effects;
  std::vector<BiasStep> bias_steps;
  std::vector<Spike> spikes;
};

struct SimulationOptions {
  double sample_rate_hz = 0.0;
  uint64_t seed = 1;
  Site site;
  // Write datasheet metadata: `datasheet` when given — the unit type's
  // specification, as a real datasheet states it — else the unit's own base
  // model (axis averages).
  bool write_datasheet = true;
  std::optional<Datasheet> datasheet;
  // Leave the sensors perfect: no drift, noise, effects, faults or quantisation
  // (for checking the mechanisation against the table's exact motion).
  bool perfect_sensors = false;
};

// Truth of one sample: drifts as they stand at the end of the sample's interval.
struct SampleTruth {
  Eigen::Vector3d gyro_gm = Eigen::Vector3d::Zero();    // base drift, rad/s
  Eigen::Vector3d acc_gm = Eigen::Vector3d::Zero();     // base drift, m/s²
  Eigen::Vector3d gyro_error = Eigen::Vector3d::Zero(); // all errors but white noise and quantisation
  Eigen::Vector3d acc_error = Eigen::Vector3d::Zero();
};

struct SimulatedRun {
  BenchRun run;
  std::vector<SampleTruth> truth;  // one per sample
  // True states of the unit's random effects, one row per sample, one column
  // per state in unit.effects order (second-order terms have two columns).
  Eigen::MatrixXd random_effect_states;
};

// Datasheet metadata of a base model: axis means of the white densities and
// correlation times, RMS over the axes of the drift σ.
Datasheet DatasheetOf(const SensorTriadModel& gyro, const SensorTriadModel& acc);

absl::StatusOr<SimulatedRun> Simulate(const SimulatedUnit& unit, const TableProfile& profile,
                                      const SimulationOptions& options);

}  // namespace insdiag::engine::sim
