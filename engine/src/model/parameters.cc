#include "insdiag/engine/model/parameters.h"

#include <cmath>
#include <numbers>

#include "insdiag/engine/model/drift_axis.h"

namespace insdiag::engine {
namespace {

constexpr const char* kAxes[] = {"x", "y", "z"};

std::string SensorUnit(Sensor s) { return s == Sensor::kGyro ? "rad/s" : "m/s^2"; }

struct BaseName {
  SensorTriadModel ErrorModel::*triad;
  const char* prefix;
  Sensor sensor;
};
constexpr BaseName kTriads[] = {{&ErrorModel::gyro, "gyro", Sensor::kGyro},
                                {&ErrorModel::acc, "acc", Sensor::kAccelerometer}};

// The bench reference's accuracy: identification may widen it (retarget.h).
struct ReferenceName {
  double ReferenceAccuracy::*sigma;
  const char* name;
  const char* unit;
};
constexpr ReferenceName kReferences[] = {
    {&ReferenceAccuracy::attitude_sigma_rad, "reference.attitude_sigma", "rad"},
    {&ReferenceAccuracy::position_sigma_m, "reference.position_sigma", "m"},
    {&ReferenceAccuracy::velocity_sigma_mps, "reference.velocity_sigma", "m/s"},
};

// Sets `field` ("" or "prior_sigma", "onset", "density", "sigma", "tau",
// "period") of parameter `parameter` of effect `e`; false when the effect's
// family has no such field.
bool SetEffectField(const std::string& field, int parameter, double value, ModelEffect& e) {
  switch (e.term.family->process) {
    case RandomProcess::kNone:
      if (field == "onset" && e.term.family->kind == EffectKind::kFault) {
        e.onset_s = value;
        return true;
      }
      if (!(field.empty() || field == "prior_sigma")) return false;
      e.prior_sigma[static_cast<size_t>(parameter)] = std::abs(value);
      return true;
    case RandomProcess::kRandomWalk:
      if (field != "density") return false;
      e.random_walk_density = value;
      return true;
    case RandomProcess::kSecondOrderMarkov:
      if (field == "sigma") {
        e.second_order_sigma = value;
      } else if (field == "tau" && value > 0.0) {
        e.second_order_alpha_per_s = 1.0 / value;
      } else if (field == "period" && value > 0.0) {
        e.second_order_beta_rad_s = 2.0 * std::numbers::pi / value;
      } else {
        return false;
      }
      return true;
  }
  return false;
}

bool Split(const std::string& name, std::string* head, std::string* tail) {
  const size_t dot = name.rfind('.');
  if (dot == std::string::npos) return false;
  *head = name.substr(0, dot);
  *tail = name.substr(dot + 1);
  return true;
}

}  // namespace

std::vector<NamedParameter> ParametersOf(const ErrorModel& model) {
  std::vector<NamedParameter> out;
  for (const BaseName& b : kTriads) {
    const SensorTriadModel& t = model.*(b.triad);
    const std::string p = b.prefix;
    const std::string u = SensorUnit(b.sensor);
    for (int i = 0; i < 3; ++i) {
      const DriftAxis drift{b.sensor, i};
      out.push_back({DriftSigmaName(drift), t.bias[static_cast<size_t>(i)].sigma, u});
      out.push_back({DriftTauName(drift), t.bias[static_cast<size_t>(i)].tau_s, "s"});
    }
    for (int i = 0; i < 3; ++i) {
      out.push_back({p + (b.sensor == Sensor::kGyro ? "_arw." : "_vrw.") + kAxes[i], t.white_noise_density[i],
                     b.sensor == Sensor::kGyro ? "rad/sqrt(s)" : "m/s/sqrt(s)"});
    }
    for (int i = 0; i < 3; ++i) {
      out.push_back({p + "_quantization." + kAxes[i], t.quantization[i], b.sensor == Sensor::kGyro ? "rad" : "m/s"});
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
          out.push_back({e.term.ParameterName(p) + ".prior_sigma", e.prior_sigma[static_cast<size_t>(p)], unit});
        }
        if (f.kind == EffectKind::kFault) out.push_back({e.term.Name() + ".onset", e.onset_s, "s"});
        break;
      case RandomProcess::kRandomWalk:
        out.push_back({e.term.Name() + ".density", e.random_walk_density, unit});
        break;
      case RandomProcess::kSecondOrderMarkov:
        out.push_back({e.term.Name() + ".sigma", e.second_order_sigma, unit});
        out.push_back({e.term.Name() + ".tau", 1.0 / e.second_order_alpha_per_s, "s"});
        out.push_back({e.term.Name() + ".period", 2.0 * std::numbers::pi / e.second_order_beta_rad_s, "s"});
        break;
    }
  }
  return out;
}

std::string ParameterUnit(const std::string& name) {
  ErrorModel probe;
  if (!SetParameter(name, 1.0, probe).ok()) return "";
  for (const NamedParameter& p : ParametersOf(probe)) {
    if (p.name == name || p.name == name + ".prior_sigma") return p.unit;
  }
  return "";
}

absl::Status SetParameter(const std::string& name, double value, ErrorModel& model) {
  std::string head, tail;
  if (Split(name, &head, &tail)) {
    for (const BaseName& b : kTriads) {
      SensorTriadModel& t = model.*(b.triad);
      const std::string p = b.prefix;
      for (int i = 0; i < 3; ++i) {
        const std::string axis = kAxes[i];
        const DriftAxis drift{b.sensor, i};
        if (name == DriftSigmaName(drift)) {
          DriftOf(model, drift).sigma = value;
          return absl::OkStatus();
        }
        if (name == DriftTauName(drift)) {
          DriftOf(model, drift).tau_s = value;
          return absl::OkStatus();
        }
        if (name == p + (b.sensor == Sensor::kGyro ? "_arw." : "_vrw.") + axis) {
          t.white_noise_density[i] = value;
          return absl::OkStatus();
        }
        if (name == p + "_quantization." + axis) {
          t.quantization[i] = value;
          return absl::OkStatus();
        }
      }
    }
  }
  for (const ReferenceName& r : kReferences) {
    if (name != r.name) continue;
    if (!(value > 0.0)) return absl::InvalidArgumentError("'" + name + "' must be positive");
    model.reference.*(r.sigma) = value;
    return absl::OkStatus();
  }
  // An effect: "<term>", "<term>.sin|cos", "<term>.prior_sigma", "<term>.onset",
  // "<term>.density|sigma|tau|period".
  std::string term_name = name;
  std::string field;
  for (const char* suffix : {".prior_sigma", ".onset", ".density", ".sigma", ".tau", ".period"}) {
    const std::string s = suffix;
    if (term_name.size() > s.size() && term_name.compare(term_name.size() - s.size(), s.size(), s) == 0) {
      field = s.substr(1);
      term_name.resize(term_name.size() - s.size());
      break;
    }
  }
  int parameter = 0;
  for (const char* suffix : {".sin", ".cos"}) {
    const std::string s = suffix;
    if (term_name.size() > s.size() && term_name.compare(term_name.size() - s.size(), s.size(), s) == 0) {
      parameter = s == ".cos" ? 1 : 0;
      term_name.resize(term_name.size() - s.size());
    }
  }
  auto terms = ParseEffectSelector(term_name);
  if (!terms.ok() || terms->size() != 1) {
    return absl::InvalidArgumentError("unknown model parameter '" + name + "'");
  }
  const EffectTerm term = terms->front();
  // Set on a copy: a refused parameter leaves the model as it was.
  const int index = model.FindEffect(term);
  ModelEffect e = index >= 0 ? model.effects[static_cast<size_t>(index)] : ModelEffect{.term = term};
  if (!SetEffectField(field, parameter, value, e)) {
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
