#include "insdiag/engine/model/parameters.h"

#include <cmath>
#include <numbers>
#include <string_view>
#include <utility>

#include "insdiag/engine/model/drift_axis.h"
#include "insdiag/engine/model/parameter_field.h"

namespace insdiag::engine {
namespace {

struct BaseName {
  SensorTriadModel ErrorModel::*triad;
  Sensor sensor;
};
constexpr BaseName kTriads[] = {{&ErrorModel::gyro, Sensor::kGyro},
                                {&ErrorModel::acc, Sensor::kAccelerometer}};

// The bench reference's accuracy: identification may widen it (retarget.h).
struct ReferenceName {
  double ReferenceAccuracy::*sigma;
  const char* name;
  const char* unit;
  bool zero_allowed = false;  // 0 is a value: the encoders read exactly
};
constexpr ReferenceName kReferences[] = {
    {&ReferenceAccuracy::attitude_sigma_rad, "reference.attitude_sigma", "rad"},
    {&ReferenceAccuracy::horizontal_position_sigma_m, "reference.horizontal_position_sigma", "m"},
    {&ReferenceAccuracy::vertical_position_sigma_m, "reference.vertical_position_sigma", "m"},
    {&ReferenceAccuracy::horizontal_velocity_sigma_mps, "reference.horizontal_velocity_sigma", "m/s"},
    {&ReferenceAccuracy::vertical_velocity_sigma_mps, "reference.vertical_velocity_sigma", "m/s"},
    {&ReferenceAccuracy::attitude_readout_sigma_rad, "reference.attitude_readout_sigma", "rad", true},
};

// One σ for a position or velocity along every axis, as models stored
// before the accuracy was stated across and along the vertical name it:
// setting it sets both, so that those models still load.
struct ReferencePairName {
  const char* name;
  double ReferenceAccuracy::*horizontal;
  double ReferenceAccuracy::*vertical;
};
constexpr ReferencePairName kReferencePairs[] = {
    {"reference.position_sigma", &ReferenceAccuracy::horizontal_position_sigma_m,
     &ReferenceAccuracy::vertical_position_sigma_m},
    {"reference.velocity_sigma", &ReferenceAccuracy::horizontal_velocity_sigma_mps,
     &ReferenceAccuracy::vertical_velocity_sigma_mps},
};

// Sets `field` of parameter `parameter` of effect `e`; false when the
// effect's family has no such field.
bool SetEffectField(ParameterField field, int parameter, double value, ModelEffect& e) {
  switch (e.term.family->process) {
    case RandomProcess::kNone:
      if (field == ParameterField::kOnset && e.term.family->kind == EffectKind::kFault) {
        e.onset_s = value;
        return true;
      }
      if (field != ParameterField::kValue && field != ParameterField::kPriorSigma) return false;
      e.prior_sigma[static_cast<size_t>(parameter)] = std::abs(value);
      return true;
    case RandomProcess::kRandomWalk:
      if (field != ParameterField::kDensity) return false;
      e.random_walk_density = value;
      return true;
    case RandomProcess::kSecondOrderMarkov:
      if (field == ParameterField::kSigma) {
        e.second_order_sigma = value;
      } else if (field == ParameterField::kTau && value > 0.0) {
        e.second_order_alpha_per_s = 1.0 / value;
      } else if (field == ParameterField::kDecayRate && value > 0.0) {
        e.second_order_alpha_per_s = value;
      } else if (field == ParameterField::kPeriod && value > 0.0) {
        e.second_order_beta_rad_s = 2.0 * std::numbers::pi / value;
      } else if (field == ParameterField::kFrequency && value > 0.0) {
        e.second_order_beta_rad_s = value;
      } else {
        return false;
      }
      return true;
    case RandomProcess::kDecayFromStart:
      if (field == ParameterField::kTau && value > 0.0) {
        e.time_constant_s = value;
        return true;
      }
      if (field != ParameterField::kValue && field != ParameterField::kPriorSigma) return false;
      e.prior_sigma[0] = std::abs(value);
      return true;
  }
  return false;
}

// A harmonic effect's parameter is named by its suffix after its term.
std::string_view SplitHarmonic(std::string_view name, int* parameter) {
  *parameter = 0;
  for (size_t index = 0; index < kHarmonicParameterSuffixes.size(); ++index) {
    const std::string_view suffix = kHarmonicParameterSuffixes[index];
    if (name.size() > suffix.size() && name.ends_with(suffix)) {
      *parameter = static_cast<int>(index);
      return name.substr(0, name.size() - suffix.size());
    }
  }
  return name;
}

}  // namespace

std::vector<NamedParameter> ParametersOf(const ErrorModel& model) {
  std::vector<NamedParameter> out;
  for (const BaseName& b : kTriads) {
    const SensorTriadModel& t = model.*(b.triad);
    const std::string u(UnitsOf(b.sensor).rate);
    for (int i = 0; i < 3; ++i) {
      const DriftAxis drift{b.sensor, i};
      out.push_back({DriftSigmaName(drift), t.bias[static_cast<size_t>(i)].sigma, u});
      out.push_back({DriftTauName(drift), t.bias[static_cast<size_t>(i)].tau_s, "s"});
    }
    for (int i = 0; i < 3; ++i) {
      out.push_back({WhiteNoiseName({b.sensor, i}), t.white_noise_density[i],
                     std::string(UnitsOf(b.sensor).white_density)});
    }
    for (int i = 0; i < 3; ++i) {
      out.push_back({QuantizationName({b.sensor, i}), t.quantization[i],
                     std::string(UnitsOf(b.sensor).quantization)});
    }
    // A flicker floor only where the model states one: a model without is
    // stated as before they were modelled.
    for (int i = 0; i < 3; ++i) {
      const FlickerFloor& f = t.flicker[static_cast<size_t>(i)];
      if (f == FlickerFloor{}) continue;
      const std::string name = FlickerName({b.sensor, i});
      out.push_back({name, f.coefficient, u});
      out.push_back({ParameterName(name, ParameterField::kShortestTau), f.shortest_tau_s, "s"});
      out.push_back({ParameterName(name, ParameterField::kLongestTau), f.longest_tau_s, "s"});
    }
  }
  for (const ReferenceName& r : kReferences) out.push_back({r.name, model.reference.*(r.sigma), r.unit});
  for (const ModelEffect& e : model.effects) {
    const EffectFamily& f = *e.term.family;
    const std::string unit(f.unit);
    switch (f.process) {
      case RandomProcess::kNone:
        for (int p = 0; p < f.parameters_per_term; ++p) {
          // A constant effect in a model is a prior; its σ is what the model states.
          out.push_back({ParameterName(e.term.ParameterName(p), ParameterField::kPriorSigma),
                         e.prior_sigma[static_cast<size_t>(p)], unit});
        }
        if (f.kind == EffectKind::kFault) {
          out.push_back({ParameterName(e.term.Name(), ParameterField::kOnset), e.onset_s, "s"});
        }
        break;
      case RandomProcess::kRandomWalk:
        out.push_back(
            {ParameterName(e.term.Name(), ParameterField::kDensity), e.random_walk_density, unit});
        break;
      case RandomProcess::kSecondOrderMarkov:
        out.push_back(
            {ParameterName(e.term.Name(), ParameterField::kSigma), e.second_order_sigma, unit});
        out.push_back({ParameterName(e.term.Name(), ParameterField::kTau),
                       1.0 / e.second_order_alpha_per_s, "s"});
        out.push_back({ParameterName(e.term.Name(), ParameterField::kPeriod),
                       2.0 * std::numbers::pi / e.second_order_beta_rad_s, "s"});
        break;
      case RandomProcess::kDecayFromStart:
        out.push_back({ParameterName(e.term.Name(), ParameterField::kPriorSigma), e.prior_sigma[0], unit});
        out.push_back({ParameterName(e.term.Name(), ParameterField::kTau), e.time_constant_s, "s"});
        break;
    }
  }
  return out;
}

std::string ParameterUnit(const std::string& name) {
  for (const ReferencePairName& pair : kReferencePairs) {
    if (name != pair.name) continue;
    for (const ReferenceName& r : kReferences) {
      if (r.sigma == pair.horizontal) return r.unit;
    }
  }
  ErrorModel probe;
  if (!SetParameter(name, 1.0, probe).ok()) return "";
  for (const NamedParameter& p : ParametersOf(probe)) {
    if (p.name == name || p.name == ParameterName(name, ParameterField::kPriorSigma)) return p.unit;
  }
  return "";
}

absl::Status SetParameter(const std::string& name, double value, ErrorModel& model) {
  for (const DriftAxis drift : DriftAxis::All()) {
    SensorTriadModel& t = drift.sensor == Sensor::kGyro ? model.gyro : model.acc;
    if (name == DriftSigmaName(drift)) {
      DriftOf(model, drift).sigma = value;
      return absl::OkStatus();
    }
    if (name == DriftTauName(drift)) {
      DriftOf(model, drift).tau_s = value;
      return absl::OkStatus();
    }
    if (name == WhiteNoiseName(drift)) {
      t.white_noise_density[drift.axis] = value;
      return absl::OkStatus();
    }
    if (name == QuantizationName(drift)) {
      t.quantization[drift.axis] = value;
      return absl::OkStatus();
    }
    const std::string flicker = FlickerName(drift);
    if (name == flicker) {
      FlickerOf(model, drift).coefficient = value;
      return absl::OkStatus();
    }
    if (name == ParameterName(flicker, ParameterField::kShortestTau)) {
      FlickerOf(model, drift).shortest_tau_s = value;
      return absl::OkStatus();
    }
    if (name == ParameterName(flicker, ParameterField::kLongestTau)) {
      FlickerOf(model, drift).longest_tau_s = value;
      return absl::OkStatus();
    }
  }
  for (const ReferenceName& r : kReferences) {
    if (name != r.name) continue;
    if (r.zero_allowed ? !(value >= 0.0) : !(value > 0.0)) {
      return absl::InvalidArgumentError("'" + name + (r.zero_allowed ? "' must not be negative" : "' must be positive"));
    }
    model.reference.*(r.sigma) = value;
    return absl::OkStatus();
  }
  for (const ReferencePairName& r : kReferencePairs) {
    if (name != r.name) continue;
    if (!(value > 0.0)) return absl::InvalidArgumentError("'" + name + "' must be positive");
    model.reference.*(r.horizontal) = value;
    model.reference.*(r.vertical) = value;
    return absl::OkStatus();
  }
  // An effect: "<term>", "<term>.sin|cos", then any field ("<term>.onset", …).
  const SplitParameter field = SplitParameterName(name);
  int parameter = 0;
  const std::string term_name(SplitHarmonic(field.quantity, &parameter));
  auto terms = ParseEffectSelector(term_name);
  if (!terms.ok() || terms->size() != 1) {
    return absl::InvalidArgumentError("unknown model parameter '" + name + "'");
  }
  const EffectTerm term = terms->front();
  // Set on a copy: a refused parameter leaves the model as it was.
  const int index = model.FindEffect(term);
  ModelEffect e = index >= 0 ? model.effects[static_cast<size_t>(index)] : ModelEffect{.term = term};
  if (!SetEffectField(field.field, parameter, value, e)) {
    return absl::InvalidArgumentError("'" + name + "' is not a parameter of " + term.Name());
  }
  if (index >= 0) {
    model.effects[static_cast<size_t>(index)] = e;
  } else {
    model.effects.push_back(e);
  }
  return absl::OkStatus();
}

}  // namespace insdiag::engine
