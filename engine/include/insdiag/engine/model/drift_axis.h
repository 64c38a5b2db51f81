// The base drifts of the error model by type: a drift is a sensor triad's
// axis (gyro x, y, z; accelerometer x, y, z), and a selection is a subset of
// the six. What names them and finds them in a model lives here once.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>

#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/model/error_model.h"

namespace insdiag::engine {

struct DriftAxis {
  Sensor sensor = Sensor::kGyro;
  int axis = 0;  // x, y, z

  static constexpr int kCount = 6;
  // Position in the order gyro x, y, z, then accelerometer x, y, z: the order
  // of All(), of a DriftSelection, and of any table kept per drift.
  constexpr int Index() const { return (sensor == Sensor::kGyro ? 0 : 3) + axis; }
  static constexpr DriftAxis FromIndex(int index) {
    return {index < 3 ? Sensor::kGyro : Sensor::kAccelerometer, index % 3};
  }
  static constexpr std::array<DriftAxis, kCount> All() {
    return {FromIndex(0), FromIndex(1), FromIndex(2), FromIndex(3), FromIndex(4), FromIndex(5)};
  }
  // The drift a term of the catalogue corrupts: its sensor's, on its axis.
  static DriftAxis Of(const EffectTerm& term) { return {term.family->sensor, term.axis}; }

  friend constexpr bool operator==(DriftAxis, DriftAxis) = default;
};

// The drift's state name ("gyro_bias_gm.x"), and the catalogue's random
// structures on it: its bias random walk ("gyro_bias_rw.x") and its
// second-order pair ("gyro_bias_second_order.x").
std::string DriftName(DriftAxis drift);
std::string WalkName(DriftAxis drift);
std::string SecondOrderName(DriftAxis drift);

// The names of the drift's parameters: "gyro_bias_gm.x.sigma", "….tau".
std::string DriftSigmaName(DriftAxis drift);
std::string DriftTauName(DriftAxis drift);
// The sensor axis's white noise ("gyro_arw.x", "acc_vrw.x") and quantization
// ("gyro_quantization.x") parameters.
std::string WhiteNoiseName(DriftAxis drift);
std::string QuantizationName(DriftAxis drift);
// The axis' flicker floor ("gyro_bias_instability.x": its B; ".tau_min",
// ".tau_max": its span).
std::string FlickerName(DriftAxis drift);
// The drift whose σ or τ `parameter` names, if it names one.
std::optional<DriftAxis> DriftOfParameter(std::string_view parameter);

// The drift's Gauss–Markov parameters in a model.
GaussMarkov& DriftOf(ErrorModel& model, DriftAxis drift);
const GaussMarkov& DriftOf(const ErrorModel& model, DriftAxis drift);
// The axis' flicker floor in a model.
FlickerFloor& FlickerOf(ErrorModel& model, DriftAxis drift);
const FlickerFloor& FlickerOf(const ErrorModel& model, DriftAxis drift);

// A subset of the six base drifts.
class DriftSelection {
 public:
  static DriftSelection None() { return {}; }
  static DriftSelection Every() {
    DriftSelection s;
    s.on_.fill(true);
    return s;
  }
  bool Contains(DriftAxis d) const { return on_[static_cast<size_t>(d.Index())]; }
  void Set(DriftAxis d, bool on = true) { on_[static_cast<size_t>(d.Index())] = on; }
  bool Any() const {
    for (bool on : on_) {
      if (on) return true;
    }
    return false;
  }
  friend bool operator==(const DriftSelection&, const DriftSelection&) = default;

 private:
  std::array<bool, DriftAxis::kCount> on_{};
};

}  // namespace insdiag::engine
