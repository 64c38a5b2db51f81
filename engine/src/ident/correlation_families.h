// The correlation families' models of the sample autocovariance and their
// fits (correlation_families.cc), which the correlation analysis
// (correlation.cc) drives. Private to the engine; the equations are in
// correlation.h.
#pragma once

#include <Eigen/Core>
#include <span>
#include <vector>

#include "insdiag/engine/ident/correlation.h"

namespace insdiag::engine::ident::correlation_families {

// The covariance of the series under a family: a stationary part R(d) (d in
// epochs) plus a random walk from the run's start, K(i, l) = q (min(i, l) + 1).
struct SeriesCovariance {
  std::vector<double> stationary;  // d = 0 … N−1
  double walk_rate = 0.0;          // q per epoch
};

// Variance of the series' mean m under K: b = (1/N²) Σ Σ K(i, l).
double MeanVariance(const SeriesCovariance& K, int N);

// The series' covariance under family f with parameters p (natural units):
// the drift's own covariance less the smoother's error covariance.
SeriesCovariance CovarianceOf(CorrelationFamily f, const double* p, int N, double dt,
                              std::span<const double> error_acf);

// Bartlett's covariance of R̂_u and R̂_v for a stationary series with autocovariance R.
double Bartlett(const std::vector<double>& R, int N, int u, int v, int M);

// The fit's data: the sample autocovariance on the lag grid, the Cholesky
// factor of its covariance, and the series it came from.
struct Problem {
  std::vector<int> lags;
  Eigen::VectorXd data;
  Eigen::MatrixXd L;  // Cholesky factor of C
  std::vector<double> error_acf;
  int N = 0;
  double dt = 0.0;
  double mean = 0.0;
  double T = 0.0;
};

// The longest decay of a second-order drift's oscillation, in periods.
constexpr double kMaxDecayInPeriods = 2.0;

// Lags 0 … max spread evenly, `count` of them (distinct).
std::vector<int> LagGrid(int max_lag, int count);

// Bartlett's C over the grid for a series of autocovariance `stationary`,
// summed to M lags.
Eigen::MatrixXd BartlettOnGrid(const Problem& pb, const std::vector<double>& stationary, int M);

// C over the grid from the exponential model (σ, τ) less the smoother's error.
Eigen::MatrixXd GridCovariance(const Problem& pb, double sigma, double tau,
                               std::vector<double>* stationary);

// Fits `family` from `start` (natural units); parameters listed in `fixed`
// stay at their start values. Covariance of the free logarithms from the
// whitened Jacobian, (JᵀJ)⁻¹, when it is well conditioned.
FamilyFit FitFamily(const Problem& pb, CorrelationFamily family, std::vector<double> start,
                    const std::vector<int>& fixed = {});

// `count` values from lo to hi spaced evenly in the logarithm.
std::vector<double> LogSpaced(double lo, double hi, int count);

// The profiled likelihood-ratio test of an alternative whose shape parameters
// vanish under the exponential: each grid point fixes them and frees one
// amplitude; the best point is then refitted with everything free for the
// reported magnitudes.
FamilyFit ProfiledAlternative(const Problem& pb, CorrelationFamily family,
                              const FamilyFit& exponential,
                              const std::vector<std::vector<double>>& grid_starts,
                              const std::vector<int>& shape);

}  // namespace insdiag::engine::ident::correlation_families
