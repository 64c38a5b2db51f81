// The unit's error model as data: the base model of seed eq. 3–6 plus any set
// of catalogue effects. The filter's state layout (state_layout.h) is derived
// from it; nothing indexes a state by a literal.
//
// Base model, per sensor axis i (seed eq. 5–6):
//   ḃ_i = −b_i/τ + σ·√(2/τ)·ξ,       R(t) = σ² e^{−|t|/τ}          Gauss–Markov drift
//   n_i white with density N (ARW [rad/√s] or VRW [m/s/√s])          (IEEE Std 952, Annex C)
//   quantisation Q (angle [rad] or velocity [m/s]), σ²_Allan = 3Q²/τ²  (IEEE Std 952, Annex C)
//   bias instability B over a span of cluster times, σ²_Allan = (2 ln 2/π) B²  (IEEE Std 952,
//   Annex C), carried as a sum of Gauss–Markov processes (model/flicker_floor.h)
// Random effects (shared/spec/effects.md):
//   bias_rw            ḃ = w,  E[w²] = K² (rate random walk density K [unit/√s])
//   bias_second_order  ẋ = (−α I + β J) x + w, E[w wᵀ] = 2ασ² I,  J = [0 −1; 1 0];
//                      the output x₁ has R(t) = σ² e^{−α|t|} cos(βt)
//                      (Gelb, Applied Optimal Estimation, 1974, Table 3.8-1: damped
//                      oscillatory process, here built from a rotating pair of states)
// Constant effects: parameters with a Gaussian prior N(0, σ_prior²) and no process noise;
// fault effects likewise, with the regressor starting at their onset;
// transient effects (warm-up) likewise, a start value b(t_s) ~ N(0, σ_prior²)
// that decays as ḃ = −b/τ with no process noise.
#pragma once

#include <absl/status/status.h>

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "insdiag/engine/model/effect_catalogue.h"

namespace insdiag::engine {

struct GaussMarkov {
  double sigma = 0.0;  // steady-state σ in the sensor's unit (rad/s or m/s²)
  double tau_s = 0.0;  // correlation time

  bool operator==(const GaussMarkov&) const = default;
};

// A bias-instability (flicker) floor: the flat Allan deviation a unit's
// drift shows over a span of cluster times, where no single Gauss–Markov
// process is flat.
struct FlickerFloor {
  double coefficient = 0.0;     // B [rad/s | m/s²]; 0 = no floor
  double shortest_tau_s = 0.0;  // the span of cluster times it holds over
  double longest_tau_s = 0.0;

  bool operator==(const FlickerFloor&) const = default;
};

// The base model of one sensor triad (gyros or accelerometers).
struct SensorTriadModel {
  std::array<GaussMarkov, 3> bias;                                // per axis
  std::array<FlickerFloor, 3> flicker{};                          // per axis, beside the drift
  Eigen::Vector3d white_noise_density = Eigen::Vector3d::Zero();  // ARW [rad/√s] | VRW [m/s/√s]
  Eigen::Vector3d quantization = Eigen::Vector3d::Zero();         // Q [rad] | [m/s]; 0 = none

  bool operator==(const SensorTriadModel&) const = default;
};

// One catalogue term in the model with its prior / process parameters.
struct ModelEffect {
  EffectTerm term;
  // kConstant families: prior σ of each parameter (index 1 used by yaw harmonics).
  std::array<double, 2> prior_sigma = {0.0, 0.0};
  // bias_rw: rate random walk density K [unit/√s].
  double random_walk_density = 0.0;
  // bias_second_order: σ [unit], α [1/s], β [rad/s].
  double second_order_sigma = 0.0;
  double second_order_alpha_per_s = 0.0;
  double second_order_beta_rad_s = 0.0;
  // kFault families: the onset t₀ [s of run time]. The filter starts the
  // fault's regressor with the first update interval whose middle is past it.
  double onset_s = 0.0;
  // kTransient families: the time constant τ [s] its start value decays
  // with (prior_sigma[0] is the start value's prior σ).
  double time_constant_s = 0.0;

  bool operator==(const ModelEffect&) const = default;
};

// Accuracy of the bench's reference: the table's attitude (initial attitude),
// the site's position and the zero velocity of the body at the table centre.
// They set the initial attitude uncertainty and the observation noise.
// Position and velocity are stated across and along the vertical: gravity is
// the one direction a unit at rest tells apart, a floor, a mount or a
// vehicle's suspension moves it differently along it, and a surveyed height
// is known less well than a surveyed place.
struct ReferenceAccuracy {
  double attitude_sigma_rad = 0.0;
  double horizontal_position_sigma_m = 0.0;  // north and east, each
  double vertical_position_sigma_m = 0.0;
  double horizontal_velocity_sigma_mps = 0.0;
  double vertical_velocity_sigma_mps = 0.0;
  // The encoders' readout noise while the table is at rest, white, per angle
  // [rad]; 0 when they read exactly (the attitude channels' rounding floor
  // applies then, filter/observation.h).
  double attitude_readout_sigma_rad = 0.0;

  bool operator==(const ReferenceAccuracy&) const = default;
};

struct ErrorModel {
  SensorTriadModel gyro;  // rad/s
  SensorTriadModel acc;   // m/s²
  std::vector<ModelEffect> effects;
  ReferenceAccuracy reference;

  // The same model to the bit: a pass of one is a pass of the other.
  bool operator==(const ErrorModel&) const = default;

  // Index of the effect with this term in `effects`, or −1.
  int FindEffect(const EffectTerm& term) const;
  // Names of the effects in the model, in model order ("gyro_scale_factor.z",
  // a fault with its onset "gyro_bias_step.x@1502", a warm-up with its time
  // constant "gyro_warm_up.x@445", …).
  std::vector<std::string> EffectNames() const;
  // Number of free parameters of the model counted by AIC/BIC: the base
  // model's noise parameters plus each effect's parameters.
  int ParameterCount() const;
};

// Adds the warm-up `term` (a kTransient family) settling with
// `time_constant_s`, its start value's prior σ `prior_sigma`, and beside it
// the steady value it settles to (SteadyValueTerm) with the same prior,
// unless the model has that already.
void AddWarmUp(const EffectTerm& term, double time_constant_s, double prior_sigma, ErrorModel& model);

// OK when every parameter is usable by the filter: σ ≥ 0, τ > 0 where σ > 0,
// noise densities and quantisation ≥ 0.
absl::Status ValidateErrorModel(const ErrorModel& model);

}  // namespace insdiag::engine
