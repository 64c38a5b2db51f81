// The filter's state vector, derived from an ErrorModel.
//
//   x = [ ψ (3) | δv (3) | δr (3) | b_g (3) | b_a (3) | effect states … ]
//   ψ   attitude error, rad, NED (phi-angle: C̃_b^n = (I − [ψ×]) C_b^n)
//   δv  velocity error, m/s, NED
//   δr  position error, m, NED (north, east, down)
//   b_g, b_a  Gauss–Markov gyro [rad/s] and accelerometer [m/s²] drifts (seed eq. 5)
// followed by the components of each flicker floor in the model (gyro x, y,
// z, then accelerometer; model/flicker_floor.h), then each model effect's
// states in model order.
//
// Every sensor state describes how it reaches the sensor outputs: the sensor
// and axis it corrupts and the regressor that multiplies it, so that the
// filter builds its couplings from this table and never from offsets.
#pragma once

#include <string>
#include <vector>

#include "insdiag/engine/model/error_model.h"

namespace insdiag::engine {

// The discrete-time dynamics class of a sensor state.
enum class StateDynamics {
  kGaussMarkov,      // φ = e^{−Δt/τ}
  kConstant,         // φ = 1, no process noise
  kRandomWalk,       // φ = 1, q = K²Δt
  kSecondOrderPair,  // first state of a 2-state block; the second follows it
  kSecondOrderTail,
  kFlickerComponent,  // φ = e^{−Δt/T_j}: component j (`parameter`) of its axis' flicker floor
  kDecaying,          // φ = e^{−Δt/τ}, no process noise: a transient's start value settling
};

struct SensorState {
  int index = 0;  // in the full state vector
  std::string name;
  Sensor sensor = Sensor::kGyro;
  int axis = 0;             // sensor axis whose output the state corrupts
  int effect = -1;          // index into ErrorModel::effects, −1 for the base drifts
  int parameter = 0;        // parameter of the effect (yaw harmonics: 0 = sin, 1 = cos)
  bool reaches_output = true;  // false for the hidden second state of a second-order pair
  StateDynamics dynamics = StateDynamics::kConstant;
};

class StateLayout {
 public:
  explicit StateLayout(const ErrorModel& model);

  int size() const { return size_; }
  static constexpr int kNavigationSize = 9;
  int attitude() const { return attitude_; }
  int velocity() const { return velocity_; }
  int position() const { return position_; }
  int gyro_bias() const { return gyro_bias_; }
  int acc_bias() const { return acc_bias_; }
  int sensor_begin() const { return kNavigationSize; }
  int sensor_count() const { return size_ - kNavigationSize; }

  // Sensor states in state order (index − sensor_begin() indexes this list).
  const std::vector<SensorState>& sensor_states() const { return sensor_states_; }
  // First state of model effect `effect_index`.
  int EffectOffset(int effect_index) const { return effect_offsets_[effect_index]; }

  // Human-readable name of state i: "att.n", "vel.e", "pos.d", "gyro_bias_gm.x",
  // "gyro_scale_factor.z", "gyro_yaw_harmonic.x.sin", "gyro_bias_second_order.x.2".
  std::string StateName(int i) const;

 private:
  int size_ = 0;
  int attitude_ = 0, velocity_ = 3, position_ = 6, gyro_bias_ = 9, acc_bias_ = 12;
  std::vector<SensorState> sensor_states_;
  std::vector<int> effect_offsets_;
};

}  // namespace insdiag::engine
