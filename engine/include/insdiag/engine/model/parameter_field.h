// A named parameter is "<quantity>.<field>": the quantity names a base term
// or an effect term ("gyro_bias_gm.x", "gyro_bias_rw.z"), the field which of
// its numbers is meant. The field suffixes are spelled here once; parse and
// build names through these, never by string search.
//
//   (none)        a constant effect's value
//   prior_sigma   a constant effect's prior σ, as the model states it
//   onset         a fault's onset in run time [s]
//   density       a random walk's K [unit/√s]
//   sigma, tau    a Gauss–Markov drift's or second-order process's σ and τ [s]
//   period        a second-order process's 2π/β [s]
//   alpha, beta   a second-order process's 1/τ [1/s] and β [rad/s], as its fit states them
//   tau_min, tau_max  the span of cluster times a flicker floor holds over [s]
#pragma once

#include <string>
#include <string_view>

namespace insdiag::engine {

enum class ParameterField {
  kValue,
  kPriorSigma,
  kOnset,
  kDensity,
  kSigma,
  kTau,
  kPeriod,
  kDecayRate,
  kFrequency,
  kShortestTau,
  kLongestTau
};

// "sigma", "tau", …; "" for kValue.
std::string_view FieldSuffix(ParameterField field);

// "<quantity>.<suffix>", or the quantity itself for kValue.
std::string ParameterName(std::string_view quantity, ParameterField field);

// A name split at its field suffix; kValue and the whole name when it ends in none.
struct SplitParameter {
  std::string_view quantity;
  ParameterField field = ParameterField::kValue;
};
SplitParameter SplitParameterName(std::string_view name);

}  // namespace insdiag::engine
