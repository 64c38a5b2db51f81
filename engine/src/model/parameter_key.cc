#include "insdiag/engine/model/parameter_key.h"

#include <absl/strings/numbers.h>
#include <absl/strings/str_cat.h>

#include <cmath>
#include <cstddef>

namespace insdiag::engine {
namespace {

int AxisIndex(char c) { return c >= 'x' && c <= 'z' ? c - 'x' : -1; }

std::optional<Sensor> SensorOfFamily(std::string_view family) {
  if (family.starts_with("gyro_")) return Sensor::kGyro;
  if (family.starts_with("acc_")) return Sensor::kAccelerometer;
  return std::nullopt;
}

// Splits a yaw harmonic's ".sin" / ".cos" off the end of `quantity`.
int SplitHarmonicPart(std::string_view& quantity) {
  for (std::size_t k = 0; k < kHarmonicParameterSuffixes.size(); ++k) {
    const std::string_view suffix = kHarmonicParameterSuffixes[k];
    if (quantity.size() > suffix.size() && quantity.ends_with(suffix)) {
      quantity.remove_suffix(suffix.size());
      return static_cast<int>(k);
    }
  }
  return -1;
}

}  // namespace

std::string_view AxisName(int axis) {
  static constexpr std::string_view kNames[3] = {"x", "y", "z"};
  return axis >= 0 && axis < 3 ? kNames[axis] : std::string_view();
}

std::optional<ParameterKey> ParseParameterKey(std::string_view name) {
  ParameterKey key;
  if (const std::size_t at = name.find('@'); at != std::string_view::npos) {
    double onset_s = 0.0;
    if (!absl::SimpleAtod(std::string(name.substr(at + 1)), &onset_s) || !std::isfinite(onset_s))
      return std::nullopt;
    key.onset_s = onset_s;
    name = name.substr(0, at);
  }
  const SplitParameter split = SplitParameterName(name);
  key.field = split.field;
  std::string_view quantity = split.quantity;
  const std::size_t dot = quantity.find('.');
  key.family = std::string(quantity.substr(0, dot));
  if (key.family.empty()) return std::nullopt;
  key.sensor = SensorOfFamily(key.family);
  key.effect_family = FindEffectFamily(key.family);
  if (dot == std::string_view::npos) return key;
  std::string_view rest = quantity.substr(dot + 1);
  if (!key.sensor) {
    // The reference's parameters ("reference.attitude_sigma") name a member, not an axis.
    key.axes = std::string(rest);
    return key;
  }
  key.harmonic = SplitHarmonicPart(rest);
  if (rest == "*") {
    key.axes = std::string(rest);  // (assigning the literal trips GCC 12's false -Wrestrict at -O3)
    return key;
  }
  if (rest.empty() || rest.size() > 2) return std::nullopt;
  for (const char c : rest) {
    if (AxisIndex(c) < 0) return std::nullopt;
  }
  key.axes = std::string(rest);
  key.axis = AxisIndex(rest.front());
  key.source_axis = AxisIndex(rest.back());
  return key;
}

std::string ParameterKey::Quantity() const {
  return axes.empty() ? family : absl::StrCat(family, ".", axes);
}

std::string ParameterKey::SensorAxis() const {
  if (!sensor || axis < 0) return "";
  return absl::StrCat(*sensor == Sensor::kGyro ? "gyro" : "acc", ".", std::string(AxisName(axis)));
}

std::optional<DriftAxis> ParameterKey::Drift() const {
  if (!sensor || axis < 0) return std::nullopt;
  return DriftAxis{*sensor, axis};
}

}  // namespace insdiag::engine
