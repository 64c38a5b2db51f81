#include "ident/correlation_families.h"

#include <ceres/ceres.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "insdiag/engine/numerics/quiet_solver.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine::ident::correlation_families {
namespace {

// The prefix sums ExpectedEstimatorInto works in, kept by a caller that
// evaluates it many times.
struct EstimatorWorkspace {
  std::vector<double> S, A;
};

// E[R̂_j] for j in `lags` (see the header), exact for N samples, into
// out[0 … lags.size()).
void ExpectedEstimatorInto(const SeriesCovariance& K, int N, std::span<const int> lags,
                           EstimatorWorkspace& ws, double* out) {
  const auto n = static_cast<size_t>(N);
  // a_i for the stationary part via prefix sums S(m) = Σ_{d ≤ m} R(d).
  std::vector<double>& S = ws.S;
  S.resize(n);
  double run = 0.0;
  for (size_t d = 0; d < n; ++d) {
    run += K.stationary[d];
    S[d] = run;
  }
  std::vector<double>& A = ws.A;  // A[m+1] = Σ_{i ≤ m} a_i
  A.resize(n + 1);
  A[0] = 0.0;
  const double q = K.walk_rate;
  for (size_t i = 0; i < n; ++i) {
    double a = (S[i] + S[n - 1 - i] - K.stationary[0]) / N;
    if (q != 0.0) {
      const double ip1 = static_cast<double>(i + 1);
      a += q / N * (ip1 * (ip1 + 1.0) / 2.0 + static_cast<double>(n - 1 - i) * ip1);
    }
    A[i + 1] = A[i] + a;
  }
  const double b = A[n] / N;
  for (size_t g = 0; g < lags.size(); ++g) {
    const auto J = static_cast<size_t>(lags[g]);
    const double count = static_cast<double>(n - J);
    double diagonal = count * K.stationary[J];
    if (q != 0.0) diagonal += q * count * (count + 1.0) / 2.0;  // Σ_{i<N−j} q (i+1)
    const double a_sum = A[n - J] + (A[n] - A[J]);              // Σ a_i + Σ a_{i+j}
    out[g] = (diagonal - a_sum + count * b) / N;
  }
}

std::vector<double> ExpectedEstimator(const SeriesCovariance& K, int N, std::span<const int> lags) {
  EstimatorWorkspace ws;
  std::vector<double> out(lags.size());
  ExpectedEstimatorInto(K, N, lags, ws, out.data());
  return out;
}

struct FamilySpec {
  CorrelationFamily family;
  std::vector<CorrelationParameter> parameters;  // all fitted as logarithms
};

// The fitted families' parameters, in the order CovarianceInto reads them.
const FamilySpec& SpecOf(CorrelationFamily family) {
  static const std::array<FamilySpec, 5> kFamilies = [] {
    using enum CorrelationParameter;
    constexpr CorrelationParameter sigma = kSigma, tau = kTau, sigma2 = kSigma2, tau2 = kTau2,
                                   period = kPeriod, density = kDensity;
    return std::array<FamilySpec, 5>{
        {{CorrelationFamily::kWhite, {sigma}},
         {CorrelationFamily::kExponential, {sigma, tau}},
         {CorrelationFamily::kExponentialCosine, {sigma, tau, sigma2, tau2, period}},
         {CorrelationFamily::kRandomWalk, {sigma, tau, density}},
         {CorrelationFamily::kTwoExponentials, {sigma, tau, sigma2, tau2}}}};
  }();
  // The exponential-plus-constant family has no entry: it is built from the exponential fit.
  return kFamilies.at(static_cast<size_t>(family));
}

// The series' covariance under a family with parameters θ (natural units) —
// the drift's own covariance less the smoother's error covariance — into K.
void CovarianceInto(CorrelationFamily f, const double* p, int N, double dt,
                    std::span<const double> error_acf, SeriesCovariance& K) {
  K.stationary.assign(static_cast<size_t>(N), 0.0);
  K.walk_rate = 0.0;
  // Exponentials and the cosine by recurrence over the lags (one exp per term).
  double first = 0.0, first_step = 0.0, second = 0.0, second_step = 0.0;
  double c = 1.0, sn = 0.0, c_step = 1.0, s_step = 0.0;
  switch (f) {
    case CorrelationFamily::kWhite:
      K.stationary[0] = p[0] * p[0];
      break;
    case CorrelationFamily::kExponential:
    case CorrelationFamily::kExponentialPlusConstant:
    case CorrelationFamily::kRandomWalk:
      first = p[0] * p[0];
      first_step = std::exp(-dt / p[1]);
      break;
    case CorrelationFamily::kExponentialCosine:
      first = p[0] * p[0];
      first_step = std::exp(-dt / p[1]);
      second = p[2] * p[2];
      second_step = std::exp(-dt / p[3]);
      c_step = std::cos(2.0 * std::numbers::pi * dt / p[4]);
      s_step = std::sin(2.0 * std::numbers::pi * dt / p[4]);
      break;
    case CorrelationFamily::kTwoExponentials:
      first = p[0] * p[0];
      first_step = std::exp(-dt / p[1]);
      second = p[2] * p[2];
      second_step = std::exp(-dt / p[3]);
      break;
  }
  if (f != CorrelationFamily::kWhite) {
    for (size_t d = 0; d < K.stationary.size(); ++d) {
      K.stationary[d] = first + second * c;
      first *= first_step;
      second *= second_step;
      if (f == CorrelationFamily::kExponentialCosine) {
        const double next_c = c * c_step - sn * s_step;
        sn = sn * c_step + c * s_step;
        c = next_c;
      }
    }
  }
  for (size_t d = 0; d < K.stationary.size() && d < error_acf.size(); ++d)
    K.stationary[d] -= error_acf[d];
  if (f == CorrelationFamily::kRandomWalk) K.walk_rate = p[2] * p[2] * dt;
}

// Whitened residuals L⁻¹ (R̂ − E[R̂]) on the lag grid, plus the mean's term.
// The solver moves the free logarithms; the others (a profile's shape) stay
// at `log_params`.
class WhitenedAcfResidual {
 public:
  WhitenedAcfResidual(CorrelationFamily family, std::vector<double> log_params,
                      std::vector<int> free_index, std::vector<int> lags, Eigen::VectorXd data,
                      Eigen::MatrixXd L, int N, double dt, std::vector<double> error_acf,
                      double mean)
      : family_(family),
        free_index_(std::move(free_index)),
        lags_(std::move(lags)),
        data_(std::move(data)),
        L_(std::move(L)),
        N_(N),
        dt_(dt),
        error_acf_(std::move(error_acf)),
        mean_(mean),
        log_params_(std::move(log_params)),
        params_(log_params_.size()),
        whitened_(static_cast<Eigen::Index>(lags_.size())) {}

  // residual = L⁻¹ ([R̂_grid; m] − [E[R̂_grid](θ); 0]) with C = L Lᵀ the covariance of
  // [R̂_grid; m] under the null; the mean's variance follows the family:
  // (m / σ_m(θ)) replaces the mean's row scale.  θ = exp(log θ).
  bool operator()(double const* const* free_log_params, double* residual) const {
    for (size_t i = 0; i < free_index_.size(); ++i) {
      log_params_[static_cast<size_t>(free_index_[i])] = free_log_params[0][i];
    }
    for (size_t i = 0; i < params_.size(); ++i) params_[i] = std::exp(log_params_[i]);
    CovarianceInto(family_, params_.data(), N_, dt_, error_acf_, covariance_);
    const SeriesCovariance& K = covariance_;
    const auto G = static_cast<Eigen::Index>(lags_.size());
    ExpectedEstimatorInto(K, N_, lags_, workspace_, whitened_.data());
    whitened_ = data_ - whitened_;
    L_.triangularView<Eigen::Lower>().solveInPlace(whitened_);
    for (Eigen::Index i = 0; i < G; ++i) residual[i] = whitened_[i];
    residual[G] = mean_ / std::sqrt(std::max(MeanVariance(K, N_), 1e-300));
    // Parameters far outside the data's range overflow: tell the solver the
    // step failed rather than hand it NaNs.
    for (Eigen::Index i = 0; i <= G; ++i) {
      if (!std::isfinite(residual[i])) return false;
    }
    return true;
  }

 private:
  CorrelationFamily family_;
  std::vector<int> free_index_;
  std::vector<int> lags_;
  Eigen::VectorXd data_;
  Eigen::MatrixXd L_;
  int N_;
  double dt_;
  std::vector<double> error_acf_;
  double mean_;
  // Scratch of every evaluation, kept to spare the allocations: the solver
  // evaluates one cost function from one thread.
  mutable std::vector<double> log_params_;
  mutable std::vector<double> params_;
  mutable SeriesCovariance covariance_;
  mutable EstimatorWorkspace workspace_;
  mutable Eigen::VectorXd whitened_;
};

// Standard errors of an alternative's parameters under that alternative.
// The fits whiten the sample ACF with Bartlett's covariance under the null
// (the exponential fit): right for the likelihood-ratio test, which is made
// under the null, but not for the alternative's magnitudes. Bartlett's
// covariance of R̂ sums products of the true autocovariance over the lags
// (Bartlett, J. R. Stat. Soc. B 8, 1946); a second-order or second slow
// component the exponential leaves out adds to that sum, so the null's
// covariance understates the sampling error of R̂ and with it that of σ₂ —
// several-fold for a σ₂ three times the base drift (a 3% error where one
// realisation of a 900 s decay over two hours scatters σ₂ by ~20%,
// tests/engine/effect_finder_test.cc). Re-whiten under the fitted alternative,
// refit from its point with the same parameters free, and take the errors
// from there; the values and the test statistics stay as they were.
void ErrorsUnderAlternative(const Problem& pb, const std::vector<int>& fixed, FamilyFit& fit) {
  if (!fit.usable) return;
  std::vector<double> p;
  double longest_s = 0.0;
  const FamilySpec& spec = SpecOf(fit.family);
  for (size_t i = 0; i < fit.parameters.size(); ++i) {
    p.push_back(fit.parameters[i].value);
    if (IsCorrelationTime(spec.parameters[i])) longest_s = std::max(longest_s, p.back());
  }
  const std::vector<double> stationary =
      CovarianceOf(fit.family, p.data(), pb.N, pb.dt, pb.error_acf).stationary;
  const int M = std::min(pb.N - 1, pb.lags.back() + static_cast<int>(6.0 * longest_s / pb.dt) + 1);
  const Eigen::LLT<Eigen::MatrixXd> llt(BartlettOnGrid(pb, stationary, M));
  if (llt.info() != Eigen::Success) return;
  Problem alternative = pb;
  alternative.L = llt.matrixL();
  const FamilyFit refit = FitFamily(alternative, fit.family, p, fixed);
  if (!refit.usable) return;
  fit.log_covariance = refit.log_covariance;
  for (size_t i = 0; i < fit.parameters.size(); ++i) {
    FittedParameter& q = fit.parameters[i];
    const double se_log =
        std::sqrt(refit.log_covariance(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i)));
    q.std_error = q.value * se_log;
    q.ci95_low = q.value * std::exp(-1.96 * se_log);
    q.ci95_high = q.value * std::exp(1.96 * se_log);
  }
}

}  // namespace

// Variance of the series' mean m under K: b = (1/N²) Σ Σ K(i, l).
double MeanVariance(const SeriesCovariance& K, int N) {
  double sum = 0.0;
  const auto n = static_cast<size_t>(N);
  for (size_t d = 0; d < n; ++d)
    sum += (d == 0 ? 1.0 : 2.0) * static_cast<double>(n - d) * K.stationary[d];
  if (K.walk_rate != 0.0) {
    // Σ_i Σ_l (min(i,l)+1) = Σ_{k=1}^{N} (2(N−k)+1) k
    double w = 0.0;
    for (size_t k = 1; k <= n; ++k)
      w += (2.0 * static_cast<double>(n - k) + 1.0) * static_cast<double>(k);
    sum += K.walk_rate * w;
  }
  return sum / (static_cast<double>(N) * N);
}

SeriesCovariance CovarianceOf(CorrelationFamily f, const double* p, int N, double dt,
                              std::span<const double> error_acf) {
  SeriesCovariance K;
  CovarianceInto(f, p, N, dt, error_acf, K);
  return K;
}

// Bartlett's covariance of R̂_u and R̂_v for a stationary series with autocovariance R.
double Bartlett(const std::vector<double>& R, int N, int u, int v, int M) {
  auto at = [&](int d) {
    d = std::abs(d);
    return d < static_cast<int>(R.size()) && d < N ? R[static_cast<size_t>(d)] : 0.0;
  };
  double s = 0.0;
  for (int m = -M; m <= M; ++m) s += at(m) * at(m + v - u) + at(m + v) * at(m - u);
  return s / N;
}

// Lags 0 … max spread evenly, `count` of them (distinct).
std::vector<int> LagGrid(int max_lag, int count) {
  std::vector<int> g;
  for (int i = 0; i < count; ++i) {
    const int lag = static_cast<int>(std::lround(static_cast<double>(max_lag) * i / (count - 1)));
    if (g.empty() || lag != g.back()) g.push_back(lag);
  }
  return g;
}

// C over the grid from the exponential model (σ, τ) less the smoother's error.
Eigen::MatrixXd GridCovariance(const Problem& pb, double sigma, double tau,
                               std::vector<double>* stationary) {
  const double p[2] = {sigma, tau};
  *stationary =
      CovarianceOf(CorrelationFamily::kExponential, p, pb.N, pb.dt, pb.error_acf).stationary;
  const int M = std::min(pb.N - 1, pb.lags.back() + static_cast<int>(6.0 * tau / pb.dt) + 1);
  return BartlettOnGrid(pb, *stationary, M);
}

Eigen::MatrixXd BartlettOnGrid(const Problem& pb, const std::vector<double>& stationary, int M) {
  const auto G = static_cast<Eigen::Index>(pb.lags.size());
  Eigen::MatrixXd C(G, G);
  for (Eigen::Index a = 0; a < G; ++a) {
    for (Eigen::Index b = a; b < G; ++b) {
      C(a, b) = C(b, a) = Bartlett(stationary, pb.N, pb.lags[static_cast<size_t>(a)],
                                   pb.lags[static_cast<size_t>(b)], M);
    }
  }
  // Loading the diagonal by a part in 10⁹ keeps the factorisation defined when
  // neighbouring lags are almost perfectly correlated.
  C.diagonal().array() += 1e-9 * C.diagonal().mean();
  return C;
}

// Fits `family` from `start` (natural units); parameters listed in `fixed`
// stay at their start values. Covariance of the free logarithms from the
// whitened Jacobian, (JᵀJ)⁻¹, when it is well conditioned.
FamilyFit FitFamily(const Problem& pb, CorrelationFamily family, std::vector<double> start,
                    const std::vector<int>& fixed) {
  const FamilySpec& spec = SpecOf(family);
  const int k = static_cast<int>(spec.parameters.size());
  std::vector<double> theta(static_cast<size_t>(k));
  for (int i = 0; i < k; ++i)
    theta[static_cast<size_t>(i)] = std::log(std::max(start[static_cast<size_t>(i)], 1e-300));
  // The solver sees the free logarithms only: a fixed one costs nothing to differentiate.
  std::vector<int> free_index;
  for (int i = 0; i < k; ++i) {
    if (std::find(fixed.begin(), fixed.end(), i) == fixed.end()) free_index.push_back(i);
  }
  const auto free_count = static_cast<int>(free_index.size());
  std::vector<double> free_theta;
  for (int i : free_index) free_theta.push_back(theta[static_cast<size_t>(i)]);

  ceres::Problem problem;
  auto* cost = new ceres::DynamicNumericDiffCostFunction<WhitenedAcfResidual, ceres::CENTRAL>(
      new WhitenedAcfResidual(family, theta, free_index, pb.lags, pb.data, pb.L, pb.N, pb.dt,
                              pb.error_acf, pb.mean));
  cost->AddParameterBlock(free_count);
  cost->SetNumResiduals(static_cast<int>(pb.lags.size()) + 1);
  problem.AddResidualBlock(cost, nullptr, free_theta.data());
  // Correlation times between a tenth of an epoch and a hundred runs.
  for (int c = 0; c < free_count; ++c) {
    if (IsTimeS(spec.parameters[static_cast<size_t>(free_index[static_cast<size_t>(c)])])) {
      problem.SetParameterLowerBound(free_theta.data(), c, std::log(0.1 * pb.dt));
      problem.SetParameterUpperBound(free_theta.data(), c, std::log(100.0 * pb.T));
    }
  }
  ceres::Solver::Options so;
  so.max_num_iterations = 200;
  so.function_tolerance = 1e-12;
  so.parameter_tolerance = 1e-12;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  numerics::QuietSolverLog();
  ceres::Solve(so, &problem, &summary);
  for (int c = 0; c < free_count; ++c) {
    theta[static_cast<size_t>(free_index[static_cast<size_t>(c)])] =
        free_theta[static_cast<size_t>(c)];
  }

  FamilyFit fit;
  fit.family = family;
  fit.parameter_count = free_count;
  fit.usable = summary.IsSolutionUsable();
  fit.stopped_at_iteration_cap = summary.termination_type == ceres::NO_CONVERGENCE;
  fit.chi2 = 2.0 * summary.final_cost;
  // Covariance of the free logarithms from the Jacobian at the solution.
  Eigen::MatrixXd cov = Eigen::MatrixXd::Constant(k, k, std::numeric_limits<double>::quiet_NaN());
  {
    double cost_value = 0.0;
    std::vector<double> residuals;
    ceres::CRSMatrix crs;
    ceres::Problem::EvaluateOptions eo;
    problem.Evaluate(eo, &cost_value, &residuals, nullptr, &crs);
    Eigen::MatrixXd Jf = Eigen::MatrixXd::Zero(crs.num_rows, free_count);
    for (int r = 0; r < crs.num_rows; ++r) {
      for (int idx = crs.rows[static_cast<size_t>(r)]; idx < crs.rows[static_cast<size_t>(r) + 1];
           ++idx) {
        Jf(r, crs.cols[static_cast<size_t>(idx)]) = crs.values[static_cast<size_t>(idx)];
      }
    }
    const Eigen::MatrixXd info = Jf.transpose() * Jf;
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(info);
    const auto& sv = svd.singularValues();
    // A direction the data do not determine leaves the standard errors unknown.
    if (sv.size() > 0 && sv(sv.size() - 1) > 1e-12 * sv(0)) {
      const Eigen::MatrixXd inv = info.inverse();
      for (size_t a = 0; a < free_index.size(); ++a) {
        for (size_t b = 0; b < free_index.size(); ++b) {
          cov(free_index[a], free_index[b]) =
              inv(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b));
        }
      }
    }
  }
  fit.log_covariance = cov;
  for (int i = 0; i < k; ++i) {
    const double v = std::exp(theta[static_cast<size_t>(i)]);
    const double se_log = std::sqrt(cov(i, i));
    fit.parameters.push_back({spec.parameters[static_cast<size_t>(i)], v, v * se_log,
                              v * std::exp(-1.96 * se_log), v * std::exp(1.96 * se_log)});
  }
  std::vector<double> natural(static_cast<size_t>(k));
  for (int i = 0; i < k; ++i)
    natural[static_cast<size_t>(i)] = std::exp(theta[static_cast<size_t>(i)]);
  const SeriesCovariance K = CovarianceOf(family, natural.data(), pb.N, pb.dt, pb.error_acf);
  std::vector<int> all(static_cast<size_t>(pb.lags.back() + 1));
  for (size_t j = 0; j < all.size(); ++j) all[j] = static_cast<int>(j);
  fit.expected = ExpectedEstimator(K, pb.N, all);
  return fit;
}

std::vector<double> LogSpaced(double lo, double hi, int count) {
  std::vector<double> v;
  if (!(hi > lo)) return {lo};
  for (int i = 0; i < count; ++i)
    v.push_back(lo * std::pow(hi / lo, static_cast<double>(i) / (count - 1)));
  return v;
}

// The profiled likelihood-ratio test of an alternative whose shape parameters
// vanish under the exponential: each grid point fixes them and frees one
// amplitude; the best point is then refitted with everything free for the
// reported magnitudes.
FamilyFit ProfiledAlternative(const Problem& pb, CorrelationFamily family,
                              const FamilyFit& exponential,
                              const std::vector<std::vector<double>>& grid_starts,
                              const std::vector<int>& shape) {
  double best_chi2 = std::numeric_limits<double>::infinity();
  const std::vector<double>* best_start = nullptr;
  FamilyFit best_on_grid;
  for (const auto& start : grid_starts) {
    FamilyFit f = FitFamily(pb, family, start, shape);
    if (f.usable && f.chi2 < best_chi2) {
      best_chi2 = f.chi2;
      best_start = &start;
      best_on_grid = std::move(f);
    }
  }
  FamilyFit out;
  out.family = family;
  if (best_start == nullptr) return out;
  out = FitFamily(pb, family, *best_start);
  const FittedParameter* decay = out.Parameter(CorrelationParameter::kTau2);
  const FittedParameter* period = out.Parameter(CorrelationParameter::kPeriod);
  const bool left_family =
      decay != nullptr && period != nullptr && decay->value > kMaxDecayInPeriods * period->value;
  const bool shape_fixed = !out.usable || out.chi2 > best_chi2 || left_family;
  if (shape_fixed) {
    // Keep the grid's point when the free fit wanders off.
    out = std::move(best_on_grid);
    out.parameter_count += static_cast<int>(shape.size());
  }
  ErrorsUnderAlternative(pb, shape_fixed ? shape : std::vector<int>{}, out);
  out.lr_statistic = std::max(0.0, exponential.chi2 - best_chi2);
  out.lr_dof = 1;
  out.lr_p_value = std::min(1.0, stats::ChiSquareSurvival(out.lr_statistic, 1.0) *
                                     static_cast<double>(grid_starts.size()));
  return out;
}

}  // namespace insdiag::engine::ident::correlation_families
