// The catalogue of physical effects in the sensor error model
// (shared/spec/effects.md): canonical names `family.axis`, what each adds to a
// sensor's error, and what table motion excites it.
//
// Measured = true + error, per sensor axis i:
//   ω̃_i = ω_i + b_g,i + Σ gyro effects + n_g,i        [rad/s]
//   f̃_i = f_i + b_a,i + Σ accelerometer effects + n_a,i  [m/s²]
//
// Constant effects are linear in their parameters p: error_i = r(u)ᵀ p, with
// the regressor r of the sample's inputs u = (ω, f, T − T0, ψ):
//   turn_on_bias.i      r = 1                         p = c_i            [rad/s | m/s²]
//   scale_factor.i      r = ω_i (f_i)                  p = s_i            [—]
//   misalignment.ij     r = ω_j (f_j), i ≠ j           p = m_ij           [—]
//   g_sensitivity.ij    r = f_j                        p = d_ij           [rad/s per m/s²]
//   temp_coeff.i        r = T − T0                     p = k_i            [rad/s/°C | m/s²/°C]
//   yaw_harmonic.i      r = (sin ψ, cos ψ)             p = (a_i, b_i)     [rad/s]
// Fault effects are constant parameters whose regressor starts at an onset
// t₀ that is estimated with them (shared/spec/effects.md):
//   bias_step.i         r = 1(t ≥ t₀)                  p = c_i            [rad/s | m/s²]
//   bias_ramp.i         r = (t − t₀)·1(t ≥ t₀)          p = r_i            [rad/s² | m/s³]
// Transient effects are a start value that decays with a time constant τ
// estimated with it, from the run's first sample t_s:
//   warm_up.i           r = e^{−(t − t_s)/τ}          p = b_i            [rad/s | m/s²]
// a bias settling as the unit warms up after power-up (a first-order
// thermal lag: the sensor's temperature, and with it its bias, approaches
// its steady state exponentially; IEEE Std 952-1997, Annex B, warm-up
// drift). The filter carries b as a state that decays with τ and has no
// process noise (model/state_layout.h).
// Random effects add states with process noise (their equations are in
// model/error_model.h).
#pragma once

#include <absl/status/statusor.h>

#include <array>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

namespace insdiag::engine {

enum class Sensor { kGyro, kAccelerometer };

// The SI units of one sensor's quantities, spelled as reports spell them.
struct SensorUnits {
  std::string_view rate;           // its output and bias: "rad/s" | "m/s^2"
  std::string_view white_density;  // angle / velocity random walk: "rad/sqrt(s)" | "m/s/sqrt(s)"
  std::string_view quantization;   // "rad" | "m/s"
  std::string_view rate_walk;      // rate random walk: "rad/s/sqrt(s)" | "m/s^2/sqrt(s)"
  std::string_view rate_ramp;      // "rad/s^2" | "m/s^3"
};
constexpr SensorUnits UnitsOf(Sensor sensor) {
  return sensor == Sensor::kGyro
             ? SensorUnits{"rad/s", "rad/sqrt(s)", "rad", "rad/s/sqrt(s)", "rad/s^2"}
             : SensorUnits{"m/s^2", "m/s/sqrt(s)", "m/s", "m/s^2/sqrt(s)", "m/s^3"};
}

enum class EffectKind {
  kConstant,  // unknown parameters: states with zero process noise
  kRandom,    // changes the structure of the drift model: states with process noise
  kFault,     // a constant that starts at an unknown onset: a state with zero process noise
  kTransient, // an unknown start value that decays with a time constant: a state with zero process noise
};

// Which axis labels a family has.
enum class AxisSet {
  kSingle,      // x, y, z
  kCrossPairs,  // xy, xz, yx, yz, zx, zy (error on i caused by the input on j, i ≠ j)
  kAllPairs,    // xx … zz
};

// What the regressor of a constant effect is (see the file comment).
enum class Regressor {
  kOne,
  kOwnInput,       // the sensor's own input on axis i
  kCrossInput,     // the sensor's own input on axis j
  kSpecificForce,  // specific force on axis j (gyro g-sensitivity)
  kTemperature,    // T − T0
  kYawSinCos,      // (sin ψ, cos ψ) of the table's reference yaw
  kStep,           // 1(t ≥ t₀)
  kRamp,           // (t − t₀)·1(t ≥ t₀)
  kNone,           // random effects
};

// What the run must contain for the effect to be excited.
enum class Excitation { kAlways, kRotation, kTilt, kTemperature };

// Random-process structure of a random or transient effect.
enum class RandomProcess {
  kNone,
  kRandomWalk,
  kSecondOrderMarkov,
  kDecayFromStart,  // ḃ = −b/τ, b(t_s) unknown, no process noise (transient effects)
};

struct EffectFamily {
  std::string_view name;
  Sensor sensor;
  EffectKind kind;
  AxisSet axes;
  Regressor regressor;
  RandomProcess process;
  int parameters_per_term;  // 2 for yaw harmonics (sin, cos); 1 otherwise
  Excitation needs;
  std::string_view unit;  // of the estimated magnitude
  std::string_view description;
};

// The whole catalogue, in the order of shared/spec/effects.md.
std::span<const EffectFamily> EffectCatalogue();

const EffectFamily* FindEffectFamily(std::string_view name);

// The suffixes that name a yaw harmonic's two parameters after its term:
// parameter k is the term's name followed by kHarmonicParameterSuffixes[k].
inline constexpr std::array<std::string_view, 2> kHarmonicParameterSuffixes = {".sin", ".cos"};

// One term of a family: the family applied to one axis (or axis pair).
struct EffectTerm {
  const EffectFamily* family = nullptr;
  int axis = 0;         // i: the sensor axis whose output the term corrupts (0..2)
  int source_axis = 0;  // j for pair families; equal to `axis` otherwise

  std::string Name() const;  // canonical "family.axis", e.g. "gyro_misalignment.xy"
  // Name of parameter k of the term: the term's name, or "….sin"/"….cos" for yaw harmonics.
  std::string ParameterName(int k) const;
  bool operator==(const EffectTerm& o) const {
    return family == o.family && axis == o.axis && source_axis == o.source_axis;
  }
};

// Every term of a family, in canonical axis order.
std::vector<EffectTerm> TermsOf(const EffectFamily& family);

// The steady value a warm-up term (kTransient) settles to: its axis' turn-on bias.
EffectTerm SteadyValueTerm(const EffectTerm& warm_up);

// Every term of the whole catalogue.
std::vector<EffectTerm> AllCatalogueTerms();

// One parameter of a constant term (yaw harmonics have two).
struct ConstantParameter {
  EffectTerm term;
  int parameter = 0;
};

// Every parameter of every constant catalogue term, in catalogue order.
std::vector<ConstantParameter> AllConstantParameters();

// Parses "family" (all its terms) or "family.axis" (one term). Unknown names
// are refused with the list of valid families or axes. A fault family may
// carry its onset, "gyro_bias_step.x@1500" (seconds of run time), and a
// warm-up its time constant, "gyro_warm_up.x@600" (seconds): see ParseOnset;
// other families refuse one.
absl::StatusOr<std::vector<EffectTerm>> ParseEffectSelector(std::string_view selector);

// The onset of a selector "name@SECONDS", nullopt when it names none;
// INVALID_ARGUMENT when the onset does not parse as a finite number.
absl::StatusOr<std::optional<double>> ParseOnset(std::string_view selector);

// One term a selector names, with the onset the selector gives it (faults),
// or the time constant (warm-ups: "gyro_warm_up.x@600").
struct SelectedTerm {
  std::string selector;  // as the user wrote it, for messages
  EffectTerm term;
  std::optional<double> onset_s;
  std::optional<double> time_constant_s;
};

// Every term of every selector, in order, with its onset; the first
// selector that does not parse refuses the whole list.
absl::StatusOr<std::vector<SelectedTerm>> ParseEffectSelectors(
    const std::vector<std::string>& selectors);

// The inputs a constant effect's regressor reads, for one sample interval.
struct RegressorInputs {
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();  // ω (measured or true)
  Eigen::Vector3d acc_mps2 = Eigen::Vector3d::Zero();    // f
  double temperature_delta_degc = 0.0;                   // T − T0
  double yaw_rad = 0.0;                                  // reference yaw ψ
  double time_since_onset_s = 0.0;                       // t − t₀ of a fault effect
};

// The regressor row(s) of a constant term: error on term.axis = rᵀ p.
// Writes parameters_per_term values into `out`.
void EvaluateRegressor(const EffectTerm& term, const RegressorInputs& in, double* out);

// The sensor error a constant term adds on each axis for parameter values `p`
// (the nonlinear-form counterpart of the regressor, used by the simulator and
// checked against EvaluateRegressor by numeric differentiation).
Eigen::Vector3d ConstantEffectError(const EffectTerm& term, const RegressorInputs& in,
                                    std::span<const double> p);

// "x", "y", "z" or pairs "xy" for an axis / axis pair.
std::string AxisLabel(AxisSet axes, int axis, int source_axis);

}  // namespace insdiag::engine
