// Two evidence terms measured together: a drift's σ and τ identified by
// likelihood, whose log errors correlate (the run tells the pair along a
// ridge, docs/DIAGNOSIS.md "A drift's σ and τ together"). A hypothesis's
// density of such a pair is bivariate: the measurement covariance
//   M = [m₁²  ρm₁m₂; ρm₁m₂  m₂²]   (ρ: the report's log_correlation)
// is added to what the hypothesis says of each term, so that a drift far
// from nominal across the ridge counts as evidence however wide each
// marginal is, and one that wandered along the ridge does not.
#pragma once

#include <array>
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "insdiag/kb/diagnosis.h"

namespace insdiag::kb::internal {

// The evidence's own terms (not the unit's trends) by name.
std::map<std::string, std::size_t> TermsByName(const Evidence& evidence);

// The index of each term's partner when two are weighed jointly
// (EvidenceTerm::jointly_with), else nullopt.
std::vector<std::optional<std::size_t>> PartnersOf(const Evidence& evidence);

// What one hypothesis says of one term of a pair.
struct PairComponent {
  const EvidenceTerm* term = nullptr;
  // The signature term that reads it (expected change, spread, directions),
  // or nullptr: the hypothesis leaves it at healthy, off with probability
  // `off_probability` for a reason it does not name.
  const Signature* reader = nullptr;
  double off_probability = 0.0;
};

// log p(x₁, x₂ | hypothesis): a mixture over which unread terms are off
// (each broad with its probability ε, the rest jointly Gaussian), averaged
// over the directions the readers allow. The kept terms are
//   N(x; μ, diag(s_h² + s²) + M),  μ_j = ±change_j and s_j = spread_j where
//   read, 0 otherwise;
// with nothing read and ε = 0 it is healthy's N(x; 0, diag(s_h²) + M).
// For one term alone this is the per-term density of diagnosis.h.
double LogPairDensity(const std::array<PairComponent, 2>& components, double correlation,
                      const DiagnosisSettings& settings);

// The squared distance of the pair from nominal for a healthy unit,
// d² = xᵀ(diag(s_h²) + M)⁻¹x: χ² on two degrees of freedom.
double PairDistanceSquared(const EvidenceTerm& first, const EvidenceTerm& second, double correlation);

}  // namespace insdiag::kb::internal
