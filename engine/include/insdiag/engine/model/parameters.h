// Named parameters of an error model — the names the knowledge base's unit
// types, the report's `identified[]` and the simulator's unit files use:
//
//   gyro_bias_gm.{x,y,z}.sigma [rad/s]   gyro_bias_gm.{x,y,z}.tau [s]
//   acc_bias_gm.{x,y,z}.sigma [m/s²]     acc_bias_gm.{x,y,z}.tau [s]
//   gyro_arw.{x,y,z} [rad/√s]            acc_vrw.{x,y,z} [m/s/√s]
//   gyro_quantization.{x,y,z} [rad]      acc_quantization.{x,y,z} [m/s]
//   reference.attitude_sigma [rad]       the bench reference's accuracy:
//   reference.{horizontal,vertical}_position_sigma [m]
//   reference.{horizontal,vertical}_velocity_sigma [m/s]
//     (reference.position_sigma and .velocity_sigma set both, as models stored earlier name them)
//   <effect term>            constant effects: the parameter value (yaw harmonics: ….sin, ….cos)
//   <effect term>.prior_sigma            the same, as the model states it: its prior σ
//   <effect term>.onset [s]  faults (bias steps and ramps): the onset in run time
//   <effect term>.density    bias_rw: K [unit/√s]
//   <effect term>.sigma / .tau / .period   bias_second_order: σ, 1/α [s], 2π/β [s]
//   <effect term>.prior_sigma / .tau     warm_up: the start value's prior σ, the time constant [s]
#pragma once

#include <absl/status/statusor.h>

#include <string>
#include <vector>

#include "insdiag/engine/model/error_model.h"

namespace insdiag::engine {

struct NamedParameter {
  std::string name;
  double value = 0.0;
  std::string unit;
};

// The base model's parameters, the reference's accuracy and each effect's, in
// a stable order: setting them all on an empty model gives `model` back (a
// second-order term's α and β to rounding, as they are stated as τ and period).
std::vector<NamedParameter> ParametersOf(const ErrorModel& model);

// The SI unit of a named parameter ("rad/s", "s", …), or "" when unknown.
std::string ParameterUnit(const std::string& name);

// Sets one named parameter of `model`; effects named by a term are added to
// the model when absent. Unknown names are refused.
absl::Status SetParameter(const std::string& name, double value, ErrorModel& model);

}  // namespace insdiag::engine
