#include "insdiag/engine/model/effect_catalogue.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>

namespace insdiag::engine {
namespace {

constexpr std::array<EffectFamily, 20> kCatalogue = {{
    {"gyro_turn_on_bias", Sensor::kGyro, EffectKind::kConstant, AxisSet::kSingle, Regressor::kOne,
     RandomProcess::kNone, 1, Excitation::kAlways, "rad/s", "run-to-run constant gyro bias c_i"},
    {"gyro_scale_factor", Sensor::kGyro, EffectKind::kConstant, AxisSet::kSingle, Regressor::kOwnInput,
     RandomProcess::kNone, 1, Excitation::kRotation, "", "gyro scale-factor error s_i·ω_i"},
    {"gyro_misalignment", Sensor::kGyro, EffectKind::kConstant, AxisSet::kCrossPairs,
     Regressor::kCrossInput, RandomProcess::kNone, 1, Excitation::kRotation, "rad",
     "gyro axis misalignment m_ij·ω_j"},
    {"gyro_g_sensitivity", Sensor::kGyro, EffectKind::kConstant, AxisSet::kAllPairs,
     Regressor::kSpecificForce, RandomProcess::kNone, 1, Excitation::kTilt, "rad/s per m/s^2",
     "gyro drift proportional to specific force d_ij·f_j"},
    {"gyro_temp_coeff", Sensor::kGyro, EffectKind::kConstant, AxisSet::kSingle, Regressor::kTemperature,
     RandomProcess::kNone, 1, Excitation::kTemperature, "rad/s/degC", "gyro bias temperature coefficient k_i·(T−T0)"},
    {"gyro_yaw_harmonic", Sensor::kGyro, EffectKind::kConstant, AxisSet::kSingle, Regressor::kYawSinCos,
     RandomProcess::kNone, 2, Excitation::kRotation, "rad/s", "gyro drift harmonic in table yaw a_i·sinψ + b_i·cosψ"},
    {"gyro_bias_rw", Sensor::kGyro, EffectKind::kRandom, AxisSet::kSingle, Regressor::kNone,
     RandomProcess::kRandomWalk, 1, Excitation::kAlways, "rad/s/sqrt(s)", "gyro rate random walk"},
    {"gyro_bias_second_order", Sensor::kGyro, EffectKind::kRandom, AxisSet::kSingle, Regressor::kNone,
     RandomProcess::kSecondOrderMarkov, 1, Excitation::kAlways, "rad/s",
     "gyro drift with correlation σ²·e^(−α|τ|)·cos(βτ)"},
    {"acc_turn_on_bias", Sensor::kAccelerometer, EffectKind::kConstant, AxisSet::kSingle, Regressor::kOne,
     RandomProcess::kNone, 1, Excitation::kAlways, "m/s^2", "run-to-run constant accelerometer bias c_i"},
    {"acc_scale_factor", Sensor::kAccelerometer, EffectKind::kConstant, AxisSet::kSingle,
     Regressor::kOwnInput, RandomProcess::kNone, 1, Excitation::kTilt, "", "accelerometer scale-factor error s_i·f_i"},
    {"acc_misalignment", Sensor::kAccelerometer, EffectKind::kConstant, AxisSet::kCrossPairs,
     Regressor::kCrossInput, RandomProcess::kNone, 1, Excitation::kTilt, "rad",
     "accelerometer axis misalignment m_ij·f_j"},
    {"acc_temp_coeff", Sensor::kAccelerometer, EffectKind::kConstant, AxisSet::kSingle,
     Regressor::kTemperature, RandomProcess::kNone, 1, Excitation::kTemperature, "m/s^2/degC",
     "accelerometer bias temperature coefficient k_i·(T−T0)"},
    {"acc_bias_rw", Sensor::kAccelerometer, EffectKind::kRandom, AxisSet::kSingle, Regressor::kNone,
     RandomProcess::kRandomWalk, 1, Excitation::kAlways, "m/s^2/sqrt(s)", "accelerometer bias random walk"},
    {"acc_bias_second_order", Sensor::kAccelerometer, EffectKind::kRandom, AxisSet::kSingle,
     Regressor::kNone, RandomProcess::kSecondOrderMarkov, 1, Excitation::kAlways, "m/s^2",
     "accelerometer bias with correlation σ²·e^(−α|τ|)·cos(βτ)"},
    {"gyro_bias_step", Sensor::kGyro, EffectKind::kFault, AxisSet::kSingle, Regressor::kStep, RandomProcess::kNone,
     1, Excitation::kAlways, "rad/s", "gyro bias jump c_i·1(t ≥ t₀) at an unknown onset t₀"},
    {"gyro_bias_ramp", Sensor::kGyro, EffectKind::kFault, AxisSet::kSingle, Regressor::kRamp, RandomProcess::kNone,
     1, Excitation::kAlways, "rad/s^2", "gyro drift rate r_i·(t − t₀)·1(t ≥ t₀) from an unknown onset t₀"},
    {"acc_bias_step", Sensor::kAccelerometer, EffectKind::kFault, AxisSet::kSingle, Regressor::kStep,
     RandomProcess::kNone, 1, Excitation::kAlways, "m/s^2", "accelerometer bias jump c_i·1(t ≥ t₀) at an unknown onset t₀"},
    {"acc_bias_ramp", Sensor::kAccelerometer, EffectKind::kFault, AxisSet::kSingle, Regressor::kRamp,
     RandomProcess::kNone, 1, Excitation::kAlways, "m/s^3",
     "accelerometer bias rate r_i·(t − t₀)·1(t ≥ t₀) from an unknown onset t₀"},
    {"gyro_warm_up", Sensor::kGyro, EffectKind::kTransient, AxisSet::kSingle, Regressor::kNone,
     RandomProcess::kDecayFromStart, 1, Excitation::kAlways, "rad/s",
     "gyro bias settling after power-up b_i·e^(−t/τ) from the run's start"},
    {"acc_warm_up", Sensor::kAccelerometer, EffectKind::kTransient, AxisSet::kSingle, Regressor::kNone,
     RandomProcess::kDecayFromStart, 1, Excitation::kAlways, "m/s^2",
     "accelerometer bias settling after power-up b_i·e^(−t/τ) from the run's start"},
}};

constexpr std::array<char, 3> kAxisNames = {'x', 'y', 'z'};

}  // namespace

std::span<const EffectFamily> EffectCatalogue() { return kCatalogue; }

const EffectFamily* FindEffectFamily(std::string_view name) {
  for (const auto& f : kCatalogue) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

std::string AxisLabel(AxisSet axes, int axis, int source_axis) {
  std::string label(1, kAxisNames[axis]);
  if (axes != AxisSet::kSingle) label += kAxisNames[source_axis];
  return label;
}

std::string EffectTerm::Name() const {
  return std::string(family->name) + "." + AxisLabel(family->axes, axis, source_axis);
}

std::string EffectTerm::ParameterName(int k) const {
  if (family->regressor == Regressor::kYawSinCos) {
    return Name() + std::string(kHarmonicParameterSuffixes[static_cast<size_t>(k)]);
  }
  return Name();
}

std::vector<EffectTerm> TermsOf(const EffectFamily& family) {
  std::vector<EffectTerm> terms;
  for (int i = 0; i < 3; ++i) {
    if (family.axes == AxisSet::kSingle) {
      terms.push_back({&family, i, i});
      continue;
    }
    for (int j = 0; j < 3; ++j) {
      if (family.axes == AxisSet::kCrossPairs && i == j) continue;
      terms.push_back({&family, i, j});
    }
  }
  return terms;
}

EffectTerm SteadyValueTerm(const EffectTerm& warm_up) {
  const std::string_view family = warm_up.family->sensor == Sensor::kGyro ? "gyro_turn_on_bias" : "acc_turn_on_bias";
  return {FindEffectFamily(family), warm_up.axis, warm_up.axis};
}

std::vector<EffectTerm> AllCatalogueTerms() {
  std::vector<EffectTerm> all;
  for (const auto& f : kCatalogue) {
    auto t = TermsOf(f);
    all.insert(all.end(), t.begin(), t.end());
  }
  return all;
}

std::vector<ConstantParameter> AllConstantParameters() {
  std::vector<ConstantParameter> out;
  for (const EffectTerm& term : AllCatalogueTerms()) {
    if (term.family->kind != EffectKind::kConstant) continue;
    for (int p = 0; p < term.family->parameters_per_term; ++p) out.push_back({term, p});
  }
  return out;
}

absl::StatusOr<std::optional<double>> ParseOnset(std::string_view selector) {
  const size_t at = selector.find('@');
  if (at == std::string_view::npos) return std::optional<double>();
  const std::string text(selector.substr(at + 1));
  char* end = nullptr;
  const double onset_s = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(onset_s)) {
    return absl::InvalidArgumentError("effect '" + std::string(selector) + "': the onset after '@' must be a number of "
                                      "seconds of run time, e.g. gyro_bias_step.x@1500");
  }
  return std::optional<double>(onset_s);
}

absl::StatusOr<std::vector<EffectTerm>> ParseEffectSelector(std::string_view full_selector) {
  const std::string_view selector = full_selector.substr(0, full_selector.find('@'));
  if (selector.size() != full_selector.size()) {
    const EffectFamily* f = FindEffectFamily(selector.substr(0, selector.find('.')));
    if (f != nullptr && f->kind != EffectKind::kFault && f->kind != EffectKind::kTransient) {
      return absl::InvalidArgumentError("effect '" + std::string(full_selector) +
                                        "': only fault effects (bias steps and ramps) take an onset '@SECONDS', "
                                        "and warm-ups a time constant");
    }
    if (auto onset = ParseOnset(full_selector); !onset.ok()) return onset.status();
  }
  const size_t dot = selector.find('.');
  const std::string_view family_name = selector.substr(0, dot);
  const EffectFamily* family = FindEffectFamily(family_name);
  if (family == nullptr) {
    std::string names;
    for (const auto& f : kCatalogue) names += (names.empty() ? "" : ", ") + std::string(f.name);
    return absl::InvalidArgumentError("unknown effect '" + std::string(selector) +
                                      "'; the catalogue has: " + names);
  }
  std::vector<EffectTerm> terms = TermsOf(*family);
  if (dot == std::string_view::npos) return terms;
  const std::string_view axis = selector.substr(dot + 1);
  std::string labels;
  for (const auto& t : terms) {
    const std::string label = AxisLabel(family->axes, t.axis, t.source_axis);
    if (label == axis) return std::vector<EffectTerm>{t};
    labels += (labels.empty() ? "" : ", ") + label;
  }
  return absl::InvalidArgumentError("effect family '" + std::string(family_name) + "' has no axis '" +
                                    std::string(axis) + "'; its axes are: " + labels);
}

absl::StatusOr<std::vector<SelectedTerm>> ParseEffectSelectors(
    const std::vector<std::string>& selectors) {
  std::vector<SelectedTerm> out;
  for (const std::string& selector : selectors) {
    auto terms = ParseEffectSelector(selector);
    if (!terms.ok()) return terms.status();
    auto onset = ParseOnset(selector);
    if (!onset.ok()) return onset.status();
    for (const EffectTerm& term : *terms) {
      if (term.family->kind != EffectKind::kTransient) {
        out.push_back({selector, term, *onset, std::nullopt});
        continue;
      }
      if (onset->has_value() && !(**onset > 0.0)) {
        return absl::InvalidArgumentError("effect '" + selector + "': a warm-up's time constant after '@' must be "
                                          "a positive number of seconds, e.g. " + term.Name() + "@600");
      }
      out.push_back({selector, term, std::nullopt, *onset});
    }
  }
  return out;
}

void EvaluateRegressor(const EffectTerm& term, const RegressorInputs& in, double* out) {
  const Eigen::Vector3d& own = term.family->sensor == Sensor::kGyro ? in.gyro_rad_s : in.acc_mps2;
  switch (term.family->regressor) {
    case Regressor::kOne:
      out[0] = 1.0;
      return;
    case Regressor::kOwnInput:
      out[0] = own[term.axis];
      return;
    case Regressor::kCrossInput:
      out[0] = own[term.source_axis];
      return;
    case Regressor::kSpecificForce:
      out[0] = in.acc_mps2[term.source_axis];
      return;
    case Regressor::kTemperature:
      out[0] = in.temperature_delta_degc;
      return;
    case Regressor::kYawSinCos:
      out[0] = std::sin(in.yaw_rad);
      out[1] = std::cos(in.yaw_rad);
      return;
    case Regressor::kStep:
      out[0] = in.time_since_onset_s >= 0.0 ? 1.0 : 0.0;
      return;
    case Regressor::kRamp:
      out[0] = std::max(0.0, in.time_since_onset_s);
      return;
    case Regressor::kNone:
      return;
  }
}

Eigen::Vector3d ConstantEffectError(const EffectTerm& term, const RegressorInputs& in,
                                    std::span<const double> p) {
  // Written from the physical definitions, independently of EvaluateRegressor,
  // so that the numeric-differentiation test compares two derivations.
  const Eigen::Vector3d& own = term.family->sensor == Sensor::kGyro ? in.gyro_rad_s : in.acc_mps2;
  Eigen::Vector3d error = Eigen::Vector3d::Zero();
  double& e = error[term.axis];
  switch (term.family->regressor) {
    case Regressor::kOne:
      e = p[0];
      break;
    case Regressor::kOwnInput:  // a scale-factor error scales the true input
      e = (1.0 + p[0]) * own[term.axis] - own[term.axis];
      break;
    case Regressor::kCrossInput:  // a small rotation of the sensing axis towards axis j
      e = std::sin(p[0]) * own[term.source_axis];
      break;
    case Regressor::kSpecificForce:
      e = p[0] * in.acc_mps2[term.source_axis];
      break;
    case Regressor::kTemperature:
      e = p[0] * in.temperature_delta_degc;
      break;
    case Regressor::kYawSinCos: {
      const double amplitude = std::hypot(p[0], p[1]);
      const double phase = std::atan2(p[1], p[0]);
      e = amplitude * std::sin(in.yaw_rad + phase);
      break;
    }
    case Regressor::kStep:  // the bias jumps at the onset and stays
      e = in.time_since_onset_s < 0.0 ? 0.0 : p[0];
      break;
    case Regressor::kRamp:  // the bias drifts at a constant rate from the onset
      e = in.time_since_onset_s < 0.0 ? 0.0 : p[0] * in.time_since_onset_s;
      break;
    case Regressor::kNone:
      break;
  }
  return error;
}

}  // namespace insdiag::engine
