#include "insdiag/engine/model/flicker_floor.h"

#include <algorithm>
#include <cmath>

#include "insdiag/engine/model/drift_axis.h"
#include "insdiag/engine/model/gauss_markov_allan.h"

namespace insdiag::engine {
namespace {

// r = 10^{3/2}: the components' spacing in T (flicker_floor.h).
const double kComponentRatio = std::pow(10.0, 1.5);
// Cluster times per decade at which the sum is matched to the floor.
constexpr int kMatchPointsPerDecade = 10;

bool HasFloor(const FlickerFloor& f) {
  return f.coefficient > 0.0 && f.shortest_tau_s > 0.0 && f.longest_tau_s >= f.shortest_tau_s;
}

}  // namespace

int FlickerComponentCount(const FlickerFloor& floor) {
  if (!HasFloor(floor)) return 0;
  const double decades_in_ratio = std::log(floor.longest_tau_s / floor.shortest_tau_s) / std::log(kComponentRatio);
  return 1 + static_cast<int>(std::ceil(decades_in_ratio - 1e-9));
}

std::vector<GaussMarkov> FlickerComponents(const FlickerFloor& floor) {
  const int n = FlickerComponentCount(floor);
  if (n == 0) return {};
  std::vector<GaussMarkov> out(static_cast<size_t>(n));
  double tau_s = floor.shortest_tau_s / MarkovShapePeak().u;
  for (GaussMarkov& c : out) {
    c.tau_s = tau_s;
    tau_s *= kComponentRatio;
  }
  const double decades = std::log10(floor.longest_tau_s / floor.shortest_tau_s);
  const int points = std::max(2, 1 + static_cast<int>(std::ceil(decades * kMatchPointsPerDecade)));
  double mean_log_shape = 0.0;
  for (int k = 0; k < points; ++k) {
    const double tau = floor.shortest_tau_s * std::pow(10.0, decades * k / (points - 1));
    double shape = 0.0;
    for (const GaussMarkov& c : out) shape += MarkovShape(tau / c.tau_s);
    mean_log_shape += std::log(shape) / points;
  }
  const double sigma = std::sqrt(kFlickerAllanVariancePerB2 * floor.coefficient * floor.coefficient / std::exp(mean_log_shape));
  for (GaussMarkov& c : out) c.sigma = sigma;
  return out;
}

FlickerFloor FlickerFloorAbove(double coefficient, double white_density, double shortest_tau_s,
                               double longest_tau_s) {
  if (!(coefficient > 0.0)) return {};
  const double floor_avar = kFlickerAllanVariancePerB2 * coefficient * coefficient;
  const double meets_white_s = white_density * white_density / floor_avar;
  const double from_s = std::max(shortest_tau_s, meets_white_s);
  if (!(from_s < longest_tau_s)) return {};
  return FlickerFloor{coefficient, from_s, longest_tau_s};
}

GaussMarkov FlickerComponentOf(const ErrorModel& model, Sensor sensor, int axis, int component) {
  const std::vector<GaussMarkov> components = FlickerComponents(FlickerOf(model, DriftAxis{sensor, axis}));
  return components.at(static_cast<size_t>(component));
}

}  // namespace insdiag::engine
