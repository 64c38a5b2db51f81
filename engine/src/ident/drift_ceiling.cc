// The largest drift the raw samples allow (drift_ceiling.h).
#include "insdiag/engine/ident/drift_ceiling.h"

#include <algorithm>
#include <cmath>
#include <complex>

#include "allan_model.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine::ident {
namespace {

// σ² g(T/τ) / σ² = g(T/τ): the drift's Allan variance per unit variance.
double MarkovAllanVariancePerVariance(double tau_s, double cluster_time_s) {
  AllanNoiseTerms unit;
  unit.markov_sigma = 1.0;
  unit.markov_tau_s = tau_s;
  return ModelAllanVariance(unit, cluster_time_s);
}

// g(u) = (2u − 3 + 4e^{−u} − e^{−2u})/u² at a complex u (the header), by
// its series where the closed form cancels (as allan_model.h's MarkovShape).
std::complex<double> MarkovShapeOfComplexRate(std::complex<double> u) {
  constexpr double kSeriesBelow = 0.1;
  if (std::abs(u) < kSeriesBelow) {
    const auto& c = allan_model::kMarkovSeries;
    std::complex<double> sum(c.back());
    for (int i = static_cast<int>(c.size()) - 2; i >= 0; --i)
      sum = sum * u + c[static_cast<size_t>(i)];
    return sum * u;
  }
  return (2.0 * u - 3.0 + 4.0 * std::exp(-u) - std::exp(-2.0 * u)) / (u * u);
}

}  // namespace

bool DriftCeilings::Allows(DriftAxis drift, const GaussMarkov& value) const {
  // A drift put on the ceiling (Within) lands on it up to rounding.
  constexpr double kRounding = 1e-12;
  return ExcessOf(drift, value).ratio <= 1.0 + kRounding;
}

DriftCeilings DriftCeilings::FromAllan(const AllanResult& allan, double family_wise_alpha) {
  size_t count = 0;
  for (const AllanChannel& ch : allan.channels) count += ch.curve.size();
  const double alpha = family_wise_alpha / static_cast<double>(std::max<size_t>(1, count));
  DriftCeilings out;
  for (const AllanChannel& ch : allan.channels) {
    for (const AllanPoint& p : ch.curve) {
      // ν of the reddest noise: the curve's own ν follows its local slope,
      // which few windows leave loose, and a bound too tight refuses the
      // unit's own drift.
      if (!(p.adev > 0.0) || !(p.edf_reddest > 0.0)) continue;
      const double lower_quantile = stats::ChiSquareQuantile(alpha, p.edf_reddest);
      if (!(lower_quantile > 0.0)) continue;
      out.Add({ch.sensor, ch.axis}, {p.tau_s, p.adev * p.adev * p.edf_reddest / lower_quantile});
    }
  }
  return out;
}

DriftCeilings::Excess DriftCeilings::ExcessOf(DriftAxis drift, const AllanNoiseTerms& terms) const {
  Excess worst;
  for (const Point& p : PointsOf(drift)) {
    const double ratio = ModelAllanVariance(terms, p.cluster_time_s) / p.allan_variance_bound;
    if (ratio > worst.ratio) worst = {ratio, p.cluster_time_s};
  }
  return worst;
}

DriftCeilings::Excess DriftCeilings::ExcessOf(DriftAxis drift, const GaussMarkov& value) const {
  if (!(value.sigma > 0.0 && value.tau_s > 0.0)) return {};
  AllanNoiseTerms terms;
  terms.markov_sigma = value.sigma;
  terms.markov_tau_s = value.tau_s;
  return ExcessOf(drift, terms);
}

DriftCeilings::Excess DriftCeilings::ExcessOf(DriftAxis drift, const AllanNoiseTerms& terms,
                                              const SecondOrderPair& pair) const {
  Excess worst;
  const std::complex<double> rate(pair.decay_rate_per_s, -pair.frequency_rad_s);
  for (const Point& p : PointsOf(drift)) {
    const double pair_variance =
        pair.sigma * pair.sigma * MarkovShapeOfComplexRate(rate * p.cluster_time_s).real();
    const double ratio =
        (ModelAllanVariance(terms, p.cluster_time_s) + pair_variance) / p.allan_variance_bound;
    if (ratio > worst.ratio) worst = {ratio, p.cluster_time_s};
  }
  return worst;
}

double DriftCeilings::LargestSigma(DriftAxis drift, double tau_s) const {
  double largest = std::numeric_limits<double>::infinity();
  for (const Point& p : PointsOf(drift)) {
    const double per_variance = MarkovAllanVariancePerVariance(tau_s, p.cluster_time_s);
    if (per_variance > 0.0)
      largest = std::min(largest, std::sqrt(p.allan_variance_bound / per_variance));
  }
  return largest;
}

GaussMarkov DriftCeilings::Within(DriftAxis drift, const GaussMarkov& value) const {
  if (Allows(drift, value)) return value;
  return {std::min(value.sigma, LargestSigma(drift, value.tau_s)), value.tau_s};
}

}  // namespace insdiag::engine::ident
