// The largest drift the raw samples allow (drift_ceiling.h).
#include "insdiag/engine/ident/drift_ceiling.h"

#include <algorithm>
#include <cmath>
#include <complex>

#include "allan_model.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine::ident {

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
  return ExcessOf(drift, terms, SecondOrderPair{});
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
        pair.sigma * pair.sigma * allan_model::MarkovShape(rate * p.cluster_time_s).real();
    const double ratio =
        (ModelAllanVariance(terms, p.cluster_time_s) + pair_variance) / p.allan_variance_bound;
    if (ratio > worst.ratio) worst = {ratio, p.cluster_time_s};
  }
  return worst;
}

double DriftCeilings::LargestSigma(DriftAxis drift, double tau_s) const {
  double largest = std::numeric_limits<double>::infinity();
  for (const Point& p : PointsOf(drift)) {
    const double per_variance =
        allan_model::MarkovShape(p.cluster_time_s / tau_s);  // σ² g(T/τ) / σ²
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
