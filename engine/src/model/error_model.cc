#include "insdiag/engine/model/error_model.h"

namespace insdiag::engine {

int ErrorModel::FindEffect(const EffectTerm& term) const {
  for (size_t k = 0; k < effects.size(); ++k) {
    if (effects[k].term == term) return static_cast<int>(k);
  }
  return -1;
}

std::vector<std::string> ErrorModel::EffectNames() const {
  std::vector<std::string> names;
  names.reserve(effects.size());
  for (const auto& e : effects) names.push_back(e.term.Name());
  return names;
}

int ErrorModel::ParameterCount() const {
  // Base: σ and τ of each of 6 drifts, and the white-noise density of each of 6 axes.
  int count = 6 * 2 + 6;
  for (const auto& e : effects) {
    switch (e.term.family->process) {
      case RandomProcess::kNone:
        count += e.term.family->parameters_per_term;
        break;
      case RandomProcess::kRandomWalk:
        count += 1;
        break;
      case RandomProcess::kSecondOrderMarkov:
        count += 3;
        break;
    }
  }
  return count;
}

}  // namespace insdiag::engine
