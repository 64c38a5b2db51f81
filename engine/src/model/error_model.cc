#include "insdiag/engine/model/error_model.h"

#include <absl/strings/str_format.h>

namespace insdiag::engine {

absl::Status ValidateErrorModel(const ErrorModel& model) {
  for (const SensorTriadModel* triad : {&model.gyro, &model.acc}) {
    for (const GaussMarkov& gm : triad->bias) {
      if (!(gm.sigma >= 0.0) || (gm.sigma > 0.0 && !(gm.tau_s > 0.0))) {
        return absl::InvalidArgumentError("error model: a Gauss–Markov drift needs σ ≥ 0 and τ > 0");
      }
    }
    for (const FlickerFloor& f : triad->flicker) {
      if (!(f.coefficient >= 0.0) ||
          (f.coefficient > 0.0 && !(f.shortest_tau_s > 0.0 && f.longest_tau_s >= f.shortest_tau_s))) {
        return absl::InvalidArgumentError("error model: a flicker floor needs B ≥ 0 and a span 0 < τ_min ≤ τ_max");
      }
    }
    if (!(triad->white_noise_density.array() >= 0.0).all() || !(triad->quantization.array() >= 0.0).all()) {
      return absl::InvalidArgumentError("error model: noise densities and quantisation must be ≥ 0");
    }
  }
  for (const ModelEffect& e : model.effects) {
    if (e.term.family->kind == EffectKind::kTransient && !(e.time_constant_s > 0.0)) {
      return absl::InvalidArgumentError("error model: " + e.term.Name() + " needs its time constant, " +
                                        e.term.Name() + ".tau > 0 [s]");
    }
  }
  return absl::OkStatus();
}

void AddWarmUp(const EffectTerm& term, double time_constant_s, double prior_sigma, ErrorModel& model) {
  if (const EffectTerm steady = SteadyValueTerm(term); model.FindEffect(steady) < 0) {
    ModelEffect constant;
    constant.term = steady;
    constant.prior_sigma[0] = prior_sigma;
    model.effects.push_back(constant);
  }
  ModelEffect e;
  e.term = term;
  e.time_constant_s = time_constant_s;
  e.prior_sigma[0] = prior_sigma;
  model.effects.push_back(e);
}

int ErrorModel::FindEffect(const EffectTerm& term) const {
  for (size_t k = 0; k < effects.size(); ++k) {
    if (effects[k].term == term) return static_cast<int>(k);
  }
  return -1;
}

std::vector<std::string> ErrorModel::EffectNames() const {
  std::vector<std::string> names;
  names.reserve(effects.size());
  for (const auto& e : effects) {
    // A fault's name carries its onset, and a warm-up's its time constant, so
    // that the name adds it back (effect_catalogue.h, ParseOnset).
    if (e.term.family->kind == EffectKind::kFault) {
      names.push_back(e.term.Name() + absl::StrFormat("@%.10g", e.onset_s));
    } else if (e.term.family->kind == EffectKind::kTransient) {
      names.push_back(e.term.Name() + absl::StrFormat("@%.10g", e.time_constant_s));
    } else {
      names.push_back(e.term.Name());
    }
  }
  return names;
}

int ErrorModel::ParameterCount() const {
  // Base: σ and τ of each of 6 drifts, and the white-noise density of each of 6 axes.
  int count = 6 * 2 + 6;
  // A flicker floor's B (its span is the Allan curve's, not fitted).
  for (const SensorTriadModel* triad : {&gyro, &acc}) {
    for (const FlickerFloor& f : triad->flicker) count += f.coefficient > 0.0 ? 1 : 0;
  }
  for (const auto& e : effects) {
    switch (e.term.family->process) {
      case RandomProcess::kNone:
        // A fault's onset is a parameter the analysis estimated as well.
        count += e.term.family->parameters_per_term + (e.term.family->kind == EffectKind::kFault ? 1 : 0);
        break;
      case RandomProcess::kRandomWalk:
        count += 1;
        break;
      case RandomProcess::kSecondOrderMarkov:
        count += 3;
        break;
      case RandomProcess::kDecayFromStart:  // the start value and τ
        count += 2;
        break;
    }
  }
  return count;
}

}  // namespace insdiag::engine
