// The Allan analysis's model of the curve, shared by its three parts
// (allan.cc: segments, curve and the analysis; allan_covariance.cc: the
// estimator's covariance; allan_fit.cc: the fit and the choice of terms).
// Private to the engine; the equations are in allan.h.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include "absl/strings/str_format.h"
#include "insdiag/engine/ident/allan.h"
#include "insdiag/engine/model/flicker_floor.h"
#include "insdiag/engine/model/gauss_markov_allan.h"

namespace insdiag::engine::ident::allan_model {

constexpr int kQ = static_cast<int>(AllanParameter::kQuantization);
constexpr int kN = static_cast<int>(AllanParameter::kWhiteDensity);
constexpr int kB = static_cast<int>(AllanParameter::kBiasInstability);
constexpr int kK = static_cast<int>(AllanParameter::kRateRandomWalk);
constexpr int kR = static_cast<int>(AllanParameter::kRateRamp);
constexpr int kMs = static_cast<int>(AllanParameter::kMarkovSigma);
constexpr int kMt = static_cast<int>(AllanParameter::kMarkovTau);
constexpr int kP = kAllanParameterCount;

// (2 ln 2/π): σ²(τ) of flicker rate noise of coefficient B (IEEE 952 Annex C).
constexpr double kFlickerAvar = kFlickerAllanVariancePerB2;

using TermMask = std::array<bool, kP>;
using LogParameters = std::array<double, kP>;

using insdiag::engine::MarkovPeak;
using insdiag::engine::MarkovShape;
using insdiag::engine::MarkovShapePeak;

// ---------------------------------------------------------------------------
// The model in log coefficients a: a_Q = ln 3Q², a_N = ln N², a_B = ln (2ln2/π)B²,
// a_K = ln K²/3, a_R = ln R²/2, a_σ = ln σ_m², a_T = ln T.

template <typename T>
T ModelAvar(const T* a, const TermMask& on, double tau) {
  using std::exp;
  T sum(0.0);
  if (on[kQ]) sum += exp(a[kQ]) / (tau * tau);
  if (on[kN]) sum += exp(a[kN]) / tau;
  if (on[kB]) sum += exp(a[kB]);
  if (on[kK]) sum += exp(a[kK]) * tau;
  if (on[kR]) sum += exp(a[kR]) * (tau * tau);
  if (on[kMs]) sum += exp(a[kMs]) * MarkovShape(T(tau) * exp(-a[kMt]));
  return sum;
}

inline AllanNoiseTerms TermsFromLog(const LogParameters& a, const TermMask& on) {
  AllanNoiseTerms t;
  if (on[kQ]) t.quantization = std::sqrt(std::exp(a[kQ]) / 3.0);
  if (on[kN]) t.white_density = std::sqrt(std::exp(a[kN]));
  if (on[kB]) t.bias_instability = std::sqrt(std::exp(a[kB]) / kFlickerAvar);
  if (on[kK]) t.rate_random_walk = std::sqrt(3.0 * std::exp(a[kK]));
  if (on[kR]) t.rate_ramp = std::sqrt(2.0 * std::exp(a[kR]));
  if (on[kMs]) {
    t.markov_sigma = std::sqrt(std::exp(a[kMs]));
    t.markov_tau_s = std::exp(a[kMt]);
  }
  return t;
}
// The curve as the fit sees it.
struct FitData {
  std::vector<size_t> point;  // index into the curve
  std::vector<int64_t> m;
  std::vector<double> tau, avar, y, s;
  double discrepancy2 = 0.0;  // δ², added to every s² (model discrepancy)
  std::vector<double> sd;     // √(s² + δ²): the weights' standard deviations

  void SetDiscrepancy(double d2) {
    discrepancy2 = d2;
    sd.resize(s.size());
    for (size_t j = 0; j < s.size(); ++j) sd[j] = std::sqrt(s[j] * s[j] + d2);
  }
};

inline int ParameterCount(const TermMask& on) { return static_cast<int>(std::count(on.begin(), on.end(), true)); }

inline std::string FormatG(double v, int digits = 3) { return absl::StrFormat("%.*g", digits, v); }

// θ_k = Σ_{i<k} (y_i − ȳ): the mean-free phase of a piece's rates (rate ×
// samples), whose differences over m samples are m times window means.
std::vector<double> PhaseOfRates(std::span<const double> rates);
// The same into `phase`, whose storage is reused.
void PhaseOfRates(std::span<const double> rates, std::vector<double>& phase);

// Differences of cluster size m in a segment of `samples` samples.
inline int64_t Differences(size_t samples, int64_t m) {
  return std::max<int64_t>(0, static_cast<int64_t>(samples) + 1 - 2 * m);
}

// Cov(σ̂²_i, σ̂²_j) for all pairs of `m` (allan_covariance.cc).
Eigen::MatrixXd EstimatorCovarianceMatrix(const AllanNoiseTerms& terms, double tau0, std::span<const int64_t> m,
                                          std::span<const size_t> segment_samples);

// V: the covariance of ln σ̂² under the model with log parameters a (allan_covariance.cc).
Eigen::MatrixXd LogAvarCovariance(const FitData& data, const LogParameters& a, const TermMask& on, double tau0,
                                  std::span<const size_t> segment_samples);

}  // namespace insdiag::engine::ident::allan_model
