#include "insdiag/engine/model/drift_axis.h"

#include <string_view>

#include "insdiag/engine/model/parameter_field.h"

namespace insdiag::engine {
namespace {

std::string_view SensorPrefix(Sensor sensor) { return sensor == Sensor::kGyro ? "gyro" : "acc"; }

// The catalogue's term of family `<sensor>_<suffix>` on the drift's axis, by name.
std::string TermName(DriftAxis drift, std::string_view suffix) {
  const std::string family = std::string(SensorPrefix(drift.sensor)) + "_" + std::string(suffix);
  return EffectTerm{FindEffectFamily(family), drift.axis, drift.axis}.Name();
}

}  // namespace

std::string DriftName(DriftAxis drift) {
  return std::string(SensorPrefix(drift.sensor)) + "_bias_gm." + AxisLabel(AxisSet::kSingle, drift.axis, drift.axis);
}

std::string DriftSigmaName(DriftAxis drift) {
  return ParameterName(DriftName(drift), ParameterField::kSigma);
}

std::string DriftTauName(DriftAxis drift) {
  return ParameterName(DriftName(drift), ParameterField::kTau);
}

std::string WhiteNoiseName(DriftAxis drift) {
  return std::string(drift.sensor == Sensor::kGyro ? "gyro_arw." : "acc_vrw.") +
         AxisLabel(AxisSet::kSingle, drift.axis, drift.axis);
}

std::string QuantizationName(DriftAxis drift) {
  return std::string(SensorPrefix(drift.sensor)) + "_quantization." +
         AxisLabel(AxisSet::kSingle, drift.axis, drift.axis);
}

std::string FlickerName(DriftAxis drift) {
  return std::string(SensorPrefix(drift.sensor)) + "_bias_instability." +
         AxisLabel(AxisSet::kSingle, drift.axis, drift.axis);
}

std::optional<DriftAxis> DriftOfParameter(std::string_view parameter) {
  for (const DriftAxis d : DriftAxis::All()) {
    if (parameter == DriftSigmaName(d) || parameter == DriftTauName(d)) return d;
  }
  return std::nullopt;
}

std::string WalkName(DriftAxis drift) { return TermName(drift, "bias_rw"); }

std::string SecondOrderName(DriftAxis drift) { return TermName(drift, "bias_second_order"); }

GaussMarkov& DriftOf(ErrorModel& model, DriftAxis drift) {
  return (drift.sensor == Sensor::kGyro ? model.gyro : model.acc).bias[static_cast<size_t>(drift.axis)];
}

const GaussMarkov& DriftOf(const ErrorModel& model, DriftAxis drift) {
  return (drift.sensor == Sensor::kGyro ? model.gyro : model.acc).bias[static_cast<size_t>(drift.axis)];
}

FlickerFloor& FlickerOf(ErrorModel& model, DriftAxis drift) {
  return (drift.sensor == Sensor::kGyro ? model.gyro : model.acc).flicker[static_cast<size_t>(drift.axis)];
}

const FlickerFloor& FlickerOf(const ErrorModel& model, DriftAxis drift) {
  return (drift.sensor == Sensor::kGyro ? model.gyro : model.acc).flicker[static_cast<size_t>(drift.axis)];
}

}  // namespace insdiag::engine
