#include "joint_evidence.h"

#include <cmath>
#include <numbers>

#include "densities.h"

namespace insdiag::kb::internal {
namespace {

// The means a signature term allows: its change in each direction.
std::vector<double> MeansOf(const Signature& s) {
  std::vector<double> means = SignsOf(s.direction);
  for (double& m : means) m *= s.change;
  return means;
}

// log N₂(x; μ, C) for a 2 × 2 covariance given by its entries.
double LogBivariateNormal(double x1, double x2, double c11, double c12, double c22) {
  const double det = c11 * c22 - c12 * c12;
  const double quad = (c22 * x1 * x1 - 2.0 * c12 * x1 * x2 + c11 * x2 * x2) / det;
  return -0.5 * (2.0 * std::log(2.0 * std::numbers::pi) + std::log(det) + quad);
}

}  // namespace

std::map<std::string, std::size_t> TermsByName(const Evidence& evidence) {
  std::map<std::string, std::size_t> index;
  for (std::size_t i = 0; i < evidence.terms.size(); ++i) {
    if (evidence.terms[i].trend_of.empty()) index.emplace(evidence.terms[i].name, i);
  }
  return index;
}

std::vector<std::optional<std::size_t>> PartnersOf(const Evidence& evidence) {
  const std::map<std::string, std::size_t> index = TermsByName(evidence);
  std::vector<std::optional<std::size_t>> out(evidence.terms.size());
  for (std::size_t i = 0; i < evidence.terms.size(); ++i) {
    const EvidenceTerm& t = evidence.terms[i];
    if (t.jointly_with.empty() || !t.trend_of.empty()) continue;
    if (const auto it = index.find(t.jointly_with); it != index.end() && it->second != i) out[i] = it->second;
  }
  return out;
}

double LogPairDensity(const std::array<PairComponent, 2>& c, double correlation,
                      const DiagnosisSettings& settings) {
  const EvidenceTerm& a = *c[0].term;
  const EvidenceTerm& b = *c[1].term;
  const double covariance = correlation * a.measurement_sd * b.measurement_sd;
  const std::vector<double> means_a = c[0].reader ? MeansOf(*c[0].reader) : std::vector<double>{0.0};
  const std::vector<double> means_b = c[1].reader ? MeansOf(*c[1].reader) : std::vector<double>{0.0};
  const double spread_a = c[0].reader ? c[0].reader->spread : 0.0;
  const double spread_b = c[1].reader ? c[1].reader->spread : 0.0;
  const double var_a = HealthyVariance(a) + spread_a * spread_a;
  const double var_b = HealthyVariance(b) + spread_b * spread_b;
  // The Gaussian part of each kept subset, averaged over the directions.
  const auto average = [](const std::vector<double>& means, auto&& density) {
    double total = -INFINITY;
    for (double m : means) total = LogAddExp(total, density(m));
    return total - std::log(static_cast<double>(means.size()));
  };
  const double both = average(means_a, [&](double ma) {
    return average(means_b, [&](double mb) {
      return LogBivariateNormal(a.x - ma, b.x - mb, var_a, covariance, var_b);
    });
  });
  const double only_a = average(means_a, [&](double ma) { return LogNormalPdf(a.x, ma, var_a); });
  const double only_b = average(means_b, [&](double mb) { return LogNormalPdf(b.x, mb, var_b); });

  // A read term is never off; an unread one is off with its ε.
  const double eps_a = c[0].reader ? 0.0 : c[0].off_probability;
  const double eps_b = c[1].reader ? 0.0 : c[1].off_probability;
  double total = std::log1p(-eps_a) + std::log1p(-eps_b) + both;
  if (eps_b > 0.0) total = LogAddExp(total, std::log1p(-eps_a) + std::log(eps_b) + only_a + LogBroad(b, settings));
  if (eps_a > 0.0) total = LogAddExp(total, std::log(eps_a) + std::log1p(-eps_b) + LogBroad(a, settings) + only_b);
  if (eps_a > 0.0 && eps_b > 0.0)
    total = LogAddExp(total, std::log(eps_a) + std::log(eps_b) + LogBroad(a, settings) + LogBroad(b, settings));
  return total;
}

double PairDistanceSquared(const EvidenceTerm& a, const EvidenceTerm& b, double correlation) {
  const double c11 = HealthyVariance(a), c22 = HealthyVariance(b);
  const double c12 = correlation * a.measurement_sd * b.measurement_sd;
  return (c22 * a.x * a.x - 2.0 * c12 * a.x * b.x + c11 * b.x * b.x) / (c11 * c22 - c12 * c12);
}

}  // namespace insdiag::kb::internal
