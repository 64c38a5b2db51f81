// A parameter's name parsed once into what it says, so that no caller
// searches the name's text for its sensor, family, axis or field:
//
//   "gyro_bias_gm.x.sigma"    gyro, family gyro_bias_gm, axes "x", field sigma
//   "acc_misalignment.xy"     accelerometer, family acc_misalignment, axes "xy"
//                             (output axis x, input axis y), a constant's value
//   "gyro_yaw_harmonic.z.cos" gyro, family gyro_yaw_harmonic, axes "z", the
//                             harmonic's cosine parameter
//   "gyro_bias_step.y.onset"  gyro, family gyro_bias_step, axes "y", field onset
//   "gyro_bias_step.y@1500"   the same term as an effect name with its onset
//   "acc_scale_factor.*"      the whole family (a signature's pattern)
//   "reference.attitude_sigma" the bench reference's accuracy: no sensor, no axis
//
// The grammar is that of parameters.h and effect_catalogue.h: the family up to
// the first '.', then the axis label ("x", "y", "z", a pair "xy", or "*"),
// then a harmonic's ".sin"/".cos", then the field suffix of parameter_field.h.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "insdiag/engine/model/drift_axis.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/model/parameter_field.h"

namespace insdiag::engine {

struct ParameterKey {
  std::string family;  // "gyro_bias_gm", "gyro_arw", "gyro_scale_factor", "reference"
  std::optional<Sensor>
      sensor;        // from the family's "gyro_" / "acc_" prefix; none for the reference
  std::string axes;  // "x", "xy", "*" (every axis of the family), "" (none); the reference's member
                     // ("attitude_sigma"), which is no axis
  int axis = -1;     // the output axis the name reads (0..2), -1 for none or "*"
  int source_axis = -1;  // a pair's input axis; equal to `axis` for one axis
  int harmonic = -1;     // a yaw harmonic's parameter: 0 sin, 1 cos; -1 otherwise
  ParameterField field = ParameterField::kValue;
  std::optional<double> onset_s;  // an effect name's "@SECONDS"

  // The catalogue family the name belongs to, nullptr for a base-model
  // parameter (drift, white noise, quantization) or the reference.
  const EffectFamily* effect_family = nullptr;

  // "family.axes" (the term or state the name reads; the family alone when it has no axes).
  std::string Quantity() const;
  // "gyro.x": the sensor axis the name reads, "" without one.
  std::string SensorAxis() const;
  // The sensor axis as a drift axis (sensor and axis), when the name reads one.
  std::optional<DriftAxis> Drift() const;
  // A whole family ("family.*").
  bool IsFamilyPattern() const { return axes == "*"; }
  // A term or state itself ("family.axes", with or without an onset): no
  // harmonic part, no field.
  bool IsBareTerm() const { return harmonic < 0 && field == ParameterField::kValue; }
};

// nullopt for a name that does not follow the grammar above (an axis label
// other than x, y, z or a pair of them, an onset that is not a number).
std::optional<ParameterKey> ParseParameterKey(std::string_view name);

// "x", "y", "z" for axis 0, 1, 2.
std::string_view AxisName(int axis);

}  // namespace insdiag::engine
