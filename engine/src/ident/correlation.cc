#include "insdiag/engine/ident/correlation.h"

#include <ceres/ceres.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string_view>

#include "ident/correlation_families.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine::ident {

using namespace correlation_families;  // the families' models and fits this analysis drives

const char* CorrelationFamilyName(CorrelationFamily f) {
  switch (f) {
    case CorrelationFamily::kWhite:
      return "white";
    case CorrelationFamily::kExponential:
      return "exponential";
    case CorrelationFamily::kExponentialCosine:
      return "exponential-cosine";
    case CorrelationFamily::kRandomWalk:
      return "random walk";
    case CorrelationFamily::kTwoExponentials:
      return "sum of two exponentials";
    case CorrelationFamily::kExponentialPlusConstant:
      return "exponential plus constant";
  }
  return "";
}

absl::Status CorrelationOptions::Validate() const {
  if (!(max_lag_in_tau > 0.0) || !(max_lag_fraction > 0.0 && max_lag_fraction < 1.0) || grid_lags < 4) {
    return absl::InvalidArgumentError("correlation options: lags out of range");
  }
  return absl::OkStatus();
}

const FittedParameter* FamilyFit::Parameter(CorrelationParameter id) const {
  for (const FittedParameter& p : parameters) {
    if (p.id == id) return &p;
  }
  return nullptr;
}

std::string_view CorrelationParameterName(CorrelationParameter p) {
  static constexpr std::array<std::string_view, 7> kNames = {
      "sigma", "tau_s", "sigma2", "tau2_s", "period_s", "density", "constant"};
  return kNames.at(static_cast<size_t>(p));
}

bool IsCorrelationTime(CorrelationParameter p) {
  return p == CorrelationParameter::kTau || p == CorrelationParameter::kTau2;
}

bool IsTimeS(CorrelationParameter p) {
  return IsCorrelationTime(p) || p == CorrelationParameter::kPeriod;
}

const FamilyFit* CorrelationAnalysis::Fit(CorrelationFamily f) const {
  for (const FamilyFit& fit : fits) {
    if (fit.family == f) return &fit;
  }
  return nullptr;
}

namespace {

std::vector<double> Centred(std::span<const double> x) {
  double m = 0.0;
  for (double v : x) m += v;
  m /= static_cast<double>(x.size());
  std::vector<double> c(x.size());
  for (size_t i = 0; i < x.size(); ++i) c[i] = x[i] - m;
  return c;
}

// Seed eq. 9 at one lag of a centred series.
double AutocovarianceAt(const std::vector<double>& centred, int lag) {
  const auto n = static_cast<int>(centred.size());
  double s = 0.0;
  for (int i = 0; i + lag < n; ++i)
    s += centred[static_cast<size_t>(i)] * centred[static_cast<size_t>(i + lag)];
  return s / n;
}

// The first lag at which the autocovariance, corrected by the smoother's
// error autocovariance, falls to 1/e of its zero lag, or 0 if it does not
// by max_lag. Lags are computed only up to the fall: on a long run the fall
// comes within a few correlation times, far short of max_lag.
int EFoldingLag(std::span<const double> series, std::span<const double> series_error_acf,
                int max_lag) {
  if (series.empty()) return 0;
  const std::vector<double> centred = Centred(series);
  auto error_at = [&](int j) {
    return j < static_cast<int>(series_error_acf.size()) ? series_error_acf[static_cast<size_t>(j)]
                                                         : 0.0;
  };
  const double threshold = (AutocovarianceAt(centred, 0) + error_at(0)) / std::numbers::e;
  const int last = std::min(max_lag, static_cast<int>(series.size()) - 1);
  for (int j = 1; j <= last; ++j) {
    if (AutocovarianceAt(centred, j) + error_at(j) <= threshold) return j;
  }
  return 0;
}

}  // namespace

std::vector<double> SampleAutocovariance(std::span<const double> x, int max_lag) {
  const auto n = static_cast<int>(x.size());
  std::vector<double> out(static_cast<size_t>(std::max(0, max_lag) + 1), 0.0);
  if (n == 0) return out;
  const std::vector<double> c = Centred(x);
  for (int j = 0; j <= max_lag && j < n; ++j) out[static_cast<size_t>(j)] = AutocovarianceAt(c, j);
  return out;
}

namespace {

// A correlation time counts as identified when its 95% interval spans less
// than this ratio (two decades would say nothing a datasheet does not).
constexpr double kMaxTauIntervalRatio = 10.0;

// Epochs per correlation time at which the series is analysed.
constexpr int kEpochsPerCorrelationTime = 20;

// The series and its smoother's error autocovariance taken at every
// `decimation`-th epoch.
struct DecimatedSeries {
  std::vector<double> series;
  std::vector<double> error_acf;
  int decimation = 1;
};

// Works at an epoch spacing of about τ/20 (τ from where the ACF falls by e):
// the estimator is the same at any spacing, and lags finer than that add
// little about a drift but cost every evaluation of the fit.
DecimatedSeries DecimateToCorrelationTime(std::span<const double> series,
                                          std::span<const double> series_error_acf,
                                          const CorrelationOptions& options) {
  DecimatedSeries out;
  const int fall =
      EFoldingLag(series, series_error_acf,
                  static_cast<int>(options.max_lag_fraction * static_cast<double>(series.size())));
  if (fall > 0) out.decimation = std::max(1, fall / kEpochsPerCorrelationTime);
  // Keep enough epochs for the lag grid (see the minimum in AnalyseCorrelation).
  const int most = static_cast<int>(series.size()) / (8 * options.grid_lags);
  out.decimation = std::max(1, std::min(out.decimation, most));
  const auto step = static_cast<size_t>(out.decimation);
  for (size_t i = 0; i < series.size(); i += step) out.series.push_back(series[i]);
  for (size_t j = 0; j < series_error_acf.size(); j += step)
    out.error_acf.push_back(series_error_acf[j]);
  return out;
}

// The exponential family's fit, iterated with the lag range and Bartlett's
// covariance that follow it: sets the problem's lags, data and covariance
// factor, and the stationary autocovariance Bartlett's formula took; σ and τ
// start at their given values and end at the fit's.
absl::StatusOr<FamilyFit> FitExponentialWithItsCovariance(Problem& pb,
                                                          const std::vector<double>& acf_full,
                                                          int capacity,
                                                          const CorrelationOptions& options,
                                                          double& sigma, double& tau,
                                                          std::vector<double>& stationary) {
  FamilyFit exponential;
  for (int pass = 0; pass < 3; ++pass) {
    const int max_lag = std::clamp(static_cast<int>(options.max_lag_in_tau * tau / pb.dt),
                                   options.grid_lags, capacity);
    pb.lags = LagGrid(max_lag, options.grid_lags);
    pb.data.resize(static_cast<Eigen::Index>(pb.lags.size()));
    for (size_t i = 0; i < pb.lags.size(); ++i) pb.data[static_cast<Eigen::Index>(i)] = acf_full[static_cast<size_t>(pb.lags[i])];
    Eigen::LLT<Eigen::MatrixXd> llt(GridCovariance(pb, sigma, tau, &stationary));
    if (llt.info() != Eigen::Success) {
      // The model less the smoother's error is no covariance when the model
      // that smoothed the series is far off (its error exceeds the drift it
      // assumes): Bartlett's formula then takes the sample autocovariance,
      // which the 1/N estimator keeps positive semi-definite (Box & Jenkins,
      // Time Series Analysis, §2.1.6).
      // Truncated to the lags analysed it may still fall short of definite
      // by rounding; its eigenvalues are then floored at a part in 10⁶ of the
      // largest (the nearest such matrix: Higham, Linear Algebra Appl. 103,
      // 1988).
      stationary.assign(acf_full.begin(), acf_full.end());
      const int M = std::min(capacity, pb.lags.back() + static_cast<int>(6.0 * tau / pb.dt) + 1);
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(BartlettOnGrid(pb, stationary, M));
      const double floor = 1e-6 * eig.eigenvalues().cwiseAbs().maxCoeff();
      if (!(floor > 0.0)) return absl::InternalError("correlation processing: covariance not positive definite");
      const Eigen::VectorXd clipped = eig.eigenvalues().cwiseMax(floor);
      llt.compute(eig.eigenvectors() * clipped.asDiagonal() * eig.eigenvectors().transpose());
      if (llt.info() != Eigen::Success) {
        return absl::InternalError("correlation processing: covariance not positive definite");
      }
    }
    pb.L = llt.matrixL();
    exponential = FitFamily(pb, CorrelationFamily::kExponential, {sigma, tau});
    const double new_tau = exponential.parameters[1].value;
    sigma = exponential.parameters[0].value;
    const bool settled = std::abs(std::log(new_tau / tau)) < 0.05;
    tau = new_tau;
    if (settled && pass > 0) break;
  }
  return exponential;
}

// The families beside the exponential, against the same data and covariance,
// each with its likelihood-ratio test against the exponential.
void FitAlternatives(const Problem& pb, const FamilyFit& exponential, double sigma, double tau,
                     double mean, std::vector<FamilyFit>& fits) {
  const double T = pb.T;
  const double lag_span = pb.lags.back() * pb.dt;
  {
    // Cosine term: a damped oscillation the lags show at least three times —
    // periods from four grid spacings (what the grid resolves) to a third of
    // the lag span, decays of half a period to kMaxDecayInPeriods; σ₂ free.
    // Slower, barely damped waves are what the sample ACF of any drift shows
    // at lags of several τ, not a second-order drift.
    std::vector<std::vector<double>> grid;
    const double grid_spacing = lag_span / static_cast<double>(pb.lags.size() - 1);
    for (double period : LogSpaced(4.0 * grid_spacing, std::min(T / 4.0, lag_span / 3.0), 8)) {
      for (double decay : {0.5, kMaxDecayInPeriods}) grid.push_back({sigma, tau, 0.5 * sigma, decay * period, period});
    }
    fits.push_back(
        ProfiledAlternative(pb, CorrelationFamily::kExponentialCosine, exponential, grid, {3, 4}));
  }
  {
    // A second, longer correlation time from 3τ to a hundred runs; σ₂ free.
    std::vector<std::vector<double>> grid;
    for (double tau2 : LogSpaced(3.0 * tau, 100.0 * T, 6)) grid.push_back({sigma, tau, 0.5 * sigma, tau2});
    fits.push_back(
        ProfiledAlternative(pb, CorrelationFamily::kTwoExponentials, exponential, grid, {3}));
  }
  {
    FamilyFit walk = FitFamily(pb, CorrelationFamily::kRandomWalk, {sigma, tau, sigma / std::sqrt(2.0 * T)});
    walk.lr_statistic = std::max(0.0, exponential.chi2 - walk.chi2);
    walk.lr_dof = 1;
    walk.lr_p_value = stats::ChiSquareSurvival(walk.lr_statistic, 1.0);
    fits.push_back(walk);
  }
  {
    // Exponential plus constant: the constant frees the mean, whose term leaves χ².
    FamilyFit constant = exponential;
    constant.family = CorrelationFamily::kExponentialPlusConstant;
    const double p[2] = {exponential.parameters[0].value, exponential.parameters[1].value};
    const double mean_sd = std::sqrt(std::max(
        MeanVariance(CovarianceOf(CorrelationFamily::kExponential, p, pb.N, pb.dt, pb.error_acf),
                     pb.N),
        0.0));
    const double mean_term = mean_sd > 0.0 ? mean / mean_sd : 0.0;
    constant.chi2 = exponential.chi2 - mean_term * mean_term;
    constant.parameter_count = exponential.parameter_count + 1;
    constant.parameters.push_back({CorrelationParameter::kConstant, mean, mean_sd,
                                   mean - 1.96 * mean_sd, mean + 1.96 * mean_sd});
    constant.lr_statistic = mean_term * mean_term;
    constant.lr_dof = 1;
    constant.lr_p_value = stats::ChiSquareSurvival(constant.lr_statistic, 1.0);
    fits.push_back(constant);
  }
}

}  // namespace

absl::StatusOr<CorrelationAnalysis> AnalyseCorrelation(std::span<const double> series,
                                                       std::span<const double> series_error_acf,
                                                       double epoch_dt,
                                                       const CorrelationOptions& options) {
  if (auto st = options.Validate(); !st.ok()) return st;
  if (!(epoch_dt > 0.0))
    return absl::InvalidArgumentError("correlation processing: epoch interval must be positive");
  const DecimatedSeries decimated = DecimateToCorrelationTime(series, series_error_acf, options);
  const std::vector<double>& smoothed = decimated.series;
  const std::vector<double>& error_acf = decimated.error_acf;
  const double dt = epoch_dt * decimated.decimation;
  const int N = static_cast<int>(smoothed.size());
  if (N < 4 * options.grid_lags) {
    return absl::FailedPreconditionError("correlation processing needs at least " +
                                         std::to_string(4 * options.grid_lags) + " epochs");
  }
  CorrelationAnalysis out;
  out.dt_s = dt;
  out.n = N;
  const int capacity = static_cast<int>(options.max_lag_fraction * N);
  const std::vector<double> acf_full = SampleAutocovariance(smoothed, capacity);
  for (double v : smoothed) out.mean += v / N;
  auto error_at = [&](int j) {
    return j < static_cast<int>(error_acf.size()) ? error_acf[static_cast<size_t>(j)] : 0.0;
  };

  // Start: σ² from the corrected zero lag, τ where the corrected ACF falls by e.
  const double r0 = acf_full[0] + error_at(0);
  if (!(r0 > 0.0))
    return absl::FailedPreconditionError("correlation processing: the series has no variance");
  int fall = capacity;
  for (int j = 1; j <= capacity; ++j) {
    if (acf_full[static_cast<size_t>(j)] + error_at(j) <= r0 / std::numbers::e) {
      fall = j;
      break;
    }
  }
  double sigma = std::sqrt(r0);
  double tau = std::max(1.0, static_cast<double>(fall)) * dt;

  Problem pb;
  pb.N = N;
  pb.dt = dt;
  pb.mean = out.mean;
  pb.T = N * dt;
  pb.error_acf.assign(error_acf.begin(), error_acf.end());
  std::vector<double> stationary;
  auto fitted =
      FitExponentialWithItsCovariance(pb, acf_full, capacity, options, sigma, tau, stationary);
  if (!fitted.ok()) return fitted.status();
  const FamilyFit exponential = std::move(*fitted);
  out.acf.assign(acf_full.begin(), acf_full.begin() + pb.lags.back() + 1);
  out.error_acf.resize(out.acf.size());
  for (size_t j = 0; j < out.acf.size(); ++j) out.error_acf[j] = error_at(static_cast<int>(j));
  {
    const int M = std::min(N - 1, pb.lags.back() + static_cast<int>(6.0 * tau / dt) + 1);
    out.acf_band.resize(out.acf.size());
    for (size_t j = 0; j < out.acf.size(); ++j) {
      out.acf_band[j] = 1.96 * std::sqrt(std::max(0.0, Bartlett(stationary, N, static_cast<int>(j),
                                                                static_cast<int>(j), M)));
    }
  }

  // Every family against the same data and covariance.
  out.fits.push_back(FitFamily(pb, CorrelationFamily::kWhite, {std::sqrt(r0)}));
  out.fits.push_back(exponential);
  FitAlternatives(pb, exponential, sigma, tau, out.mean, out.fits);
  const double log_n = std::log(static_cast<double>(pb.lags.size() + 1));
  double best_aic = std::numeric_limits<double>::infinity();
  for (FamilyFit& f : out.fits) {
    f.aic = f.chi2 + 2.0 * f.parameter_count;
    f.bic = f.chi2 + f.parameter_count * log_n;
    if (f.usable && f.bic < best_aic) {
      best_aic = f.bic;
      out.best = f.family;
    }
  }
  // Resolved: the smoother's error is a minor part of the drift's variance as
  // the data show it (R̂(0) + R_e(0)), and the data bound τ — a finite interval
  // narrower than kMaxTauIntervalRatio, below half the run.
  out.unresolved_fraction = error_at(0) / (acf_full[0] + error_at(0));
  const FittedParameter& tau_fit = exponential.parameters[1];
  const bool tau_bounded = std::isfinite(tau_fit.std_error) && tau_fit.ci95_high < 0.5 * pb.T &&
                           tau_fit.ci95_high < kMaxTauIntervalRatio * tau_fit.ci95_low;
  out.resolved = exponential.usable && tau_bounded &&
                 out.unresolved_fraction <= options.max_unresolved_fraction;
  return out;
}

}  // namespace insdiag::engine::ident
