// Correlation processing of a smoothed sensor-error estimate (seed eq. 8–9)
// and structural identification of its correlation function.
//
// Estimator (seed eq. 9): R̂_j = (1/N) Σ_{i=0}^{N−1−j} (x_i − m)(x_{i+j} − m),  m = (1/N) Σ x_i.
//
// What R̂ estimates. The smoothed estimate x̂ = x − e is orthogonal to its own
// error e, so its covariance is K_x − K_e (K_e from the smoother, SmoothedPass::
// error_autocovariance), and the 1/N, mean-removed estimator is biased by the
// mean's removal. For any covariance K(i, l) of the series,
//   E[R̂_j] = (1/N) Σ_{i=0}^{N−1−j} [K(i, i+j) − a_i − a_{i+j} + b],
//   a_i = (1/N) Σ_l K(i, l),  b = (1/N) Σ_i a_i,
// which is evaluated exactly in O(N) (prefix sums). Each family is fitted to
// R̂ through this expectation, so the fit is unbiased for finite runs and for
// drifts the run only partly resolves.
//
// Families (σ² variance, τ correlation time, Δ = lag in s):
//   white              R(Δ) = σ² δ(Δ)
//   exponential        R(Δ) = σ² e^{−|Δ|/τ}                       (seed eq. 6, the base model)
//   exponential + exponential-cosine   + σ₂² e^{−|Δ|/τ₂} cos(2πΔ/P)   (second-order Markov)
//   exponential + random walk          + K² min(t_i, t_l)             (rate random walk, from the run's start)
//   sum of two exponentials            + σ₂² e^{−|Δ|/τ₂}, τ₂ > τ
//   exponential + constant             + c² (a turn-on bias: the mean removal hides it from R̂,
//                                        so it is tested on the mean m itself)
//
// Fit (seed eq. 8, generalised): minimise rᵀ C⁻¹ r with r = R̂ − E[R̂] on a
// grid of lags, C the covariance of R̂ across lags by Bartlett's formula
// (Bartlett 1946; Priestley, Spectral Analysis and Time Series, 1981, eq. 5.3.21)
//   Cov(R̂_u, R̂_v) ≈ (1/N) Σ_m [R(m) R(m+v−u) + R(m+v) R(m−u)]
// evaluated with the exponential fit; parameters in logarithms (positive),
// standard errors from the Jacobian at the solution (Ceres Covariance) and
// 95% intervals on the log scale. Families are compared by
// AIC = rᵀC⁻¹r + 2k and BIC = rᵀC⁻¹r + k ln(G+1) over the G grid lags and the
// mean (Akaike 1974; Schwarz 1978), with the same C for all.
//
// Whether a family beats the exponential is a likelihood-ratio test,
// Δχ² = χ²_exponential − χ²_family. Where the alternative has parameters
// that vanish under the null (the period and decay of the cosine term, the
// second correlation time), the null distribution is not χ² (Davies,
// Biometrika 74(1), 1987): those parameters are profiled over a grid, the
// statistic is the grid's largest Δχ² (one free amplitude, χ²(1) at each
// point) and its p-value is Bonferroni-corrected over the grid. These
// p-values screen: at run lengths of tens of τ, R̂'s long-lag wander is not
// Gaussian enough for them to be exact (an oscillatory alternative fits it in
// a few per cent of drift-free runs), so the analysis confirms a screened
// structure with the filter's exact likelihood before reporting it.
#pragma once

#include <absl/status/statusor.h>

#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace insdiag::engine::ident {

enum class CorrelationFamily {
  kWhite,
  kExponential,
  kExponentialCosine,  // exponential + exponential-cosine
  kRandomWalk,         // exponential + random walk
  kTwoExponentials,
  kExponentialPlusConstant,
};
const char* CorrelationFamilyName(CorrelationFamily f);

// Seed eq. 9 for lags 0 … max_lag.
std::vector<double> SampleAutocovariance(std::span<const double> x, int max_lag);

// A correlation family's parameters: the first exponential's σ and τ, the
// second term's σ₂ and τ₂ (decay time) with its period, a walk's density,
// and the exponential-plus-constant family's constant.
enum class CorrelationParameter { kSigma, kTau, kSigma2, kTau2, kPeriod, kDensity, kConstant };
// The name reports give it: "sigma", "tau_s", "sigma2", "tau2_s", "period_s", "density",
// "constant".
std::string_view CorrelationParameterName(CorrelationParameter p);
// True for the times [s] (τ, τ₂, the period); the others are in the drift's
// unit, the density per √s.
bool IsTimeS(CorrelationParameter p);
// A correlation time of the family (τ or τ₂), not its period.
bool IsCorrelationTime(CorrelationParameter p);

struct FittedParameter {
  CorrelationParameter id = CorrelationParameter::kSigma;
  double value = 0.0;
  double std_error = 0.0;
  double ci95_low = 0.0;
  double ci95_high = 0.0;

  std::string_view Name() const { return CorrelationParameterName(id); }
};

struct FamilyFit {
  CorrelationFamily family = CorrelationFamily::kExponential;
  // The solver ended at a point worth reading: converged, or stopped at its
  // iteration cap (then said by stopped_at_iteration_cap).
  bool usable = false;
  bool stopped_at_iteration_cap = false;
  std::vector<FittedParameter> parameters;
  double chi2 = 0.0;  // rᵀ C⁻¹ r plus the mean's term (m/σ_m)²
  int parameter_count = 0;
  double aic = 0.0;
  double bic = 0.0;
  // Against the exponential (zero for the exponential and white families).
  double lr_statistic = 0.0;
  int lr_dof = 0;
  double lr_p_value = 1.0;
  std::vector<double> expected;  // E[R̂] at every lag 0 … max_lag under the fit
  // Covariance of the logarithms of the parameters (NaN where undetermined).
  Eigen::MatrixXd log_covariance;

  // The fit's parameter `id`, or nullptr when the family has none.
  const FittedParameter* Parameter(CorrelationParameter id) const;
};

struct CorrelationOptions {
  // Largest lag fitted, in correlation times of the first exponential fit …
  double max_lag_in_tau = 5.0;
  // … and at most this share of the series.
  double max_lag_fraction = 0.4;
  int grid_lags = 40;  // lags in the fit's grid
  // A drift is identified only when the data resolve it: the smoother's mean
  // error variance is at most this share of the series' variance, and τ's
  // 95% interval is bounded (see correlation.cc).
  double max_unresolved_fraction = 0.5;

  absl::Status Validate() const;
};

struct CorrelationAnalysis {
  double dt_s = 0.0;  // epoch spacing of the analysis (the series decimated to about τ/20)
  int n = 0;
  std::vector<double> acf;             // R̂_j, j = 0 … max_lag (seed eq. 9)
  std::vector<double> acf_band;        // ±1.96·√Var(R̂_j) under the exponential fit
  std::vector<double> error_acf;       // R_e(j) the smoother adds back
  double mean = 0.0;                   // m
  std::vector<FamilyFit> fits;         // every family tried
  CorrelationFamily best = CorrelationFamily::kExponential;  // by BIC
  bool resolved = false;               // the data resolve the drift (see options)
  double unresolved_fraction = 0.0;    // R_e(0) / (R̂(0) + R_e(0))

  const FamilyFit* Fit(CorrelationFamily f) const;
};

// `smoothed`: the smoothed estimate of one drift state at equally spaced epochs
// dt_s apart; `error_acf`: R_e(j) for j = 0 … (at least) the lags used.
absl::StatusOr<CorrelationAnalysis> AnalyseCorrelation(std::span<const double> smoothed,
                                                       std::span<const double> error_acf, double dt_s,
                                                       const CorrelationOptions& options);

}  // namespace insdiag::engine::ident
