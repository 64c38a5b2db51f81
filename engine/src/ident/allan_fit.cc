// The Allan curve's fit (allan.h): weighted least squares of ln σ̂² in
// Ceres, the choice of terms by their Wald z, the adequacy test and the
// model discrepancy.
#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <string>

#include "ident/allan_model.h"
#include "insdiag/engine/numerics/quiet_solver.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine::ident {
namespace {

using namespace allan_model;  // the curve's model, shared with the analysis and the covariance

// Basis of the linear terms: σ² = Σ_k c_k φ_k(τ), c = e^a.
double Basis(int k, double tau, double markov_tau_s) {
  switch (k) {
    case kQ: return 1.0 / (tau * tau);
    case kN: return 1.0 / tau;
    case kB: return 1.0;
    case kK: return tau;
    case kR: return tau * tau;
    case kMs: return MarkovShape(tau / markov_tau_s);
    default: return 0.0;
  }
}

int TermCount(const TermMask& on) {
  int n = 0;
  for (int k = 0; k < kMs; ++k) n += on[static_cast<size_t>(k)] ? 1 : 0;
  return n + (on[kMs] ? 1 : 0);
}

// One point of the curve (house style: measurement and √information as members):
//   r = (y − ln σ²(τ; a)) · √I,
//   y = ln σ̂² − [ψ(ν/2) − ln(ν/2)]   (ln σ̂² corrected for the mean of ln χ²_ν/ν)
//   √I = 1/√ψ′(ν/2)                   (the standard deviation of ln χ²_ν)
class AllanLogResidual {
 public:
  AllanLogResidual(double tau_s, double measurement, double sqrt_information, const TermMask& on)
      : tau_s_(tau_s), measurement_(measurement), sqrt_information_(sqrt_information), on_(on) {}

  template <typename T>
  bool operator()(const T* const a, T* residual) const {
    using std::log;
    residual[0] = (T(measurement_) - log(ModelAvar(a, on_, tau_s_))) * sqrt_information_;
    return true;
  }

  static ceres::CostFunction* Create(double tau_s, double measurement, double sqrt_information,
                                     const TermMask& on) {
    return new ceres::AutoDiffCostFunction<AllanLogResidual, 1, kP>(
        new AllanLogResidual(tau_s, measurement, sqrt_information, on));
  }

 private:
  double tau_s_;
  double measurement_;
  double sqrt_information_;
  TermMask on_;
};

// ---------------------------------------------------------------------------
// Fitting.

struct Bounds {
  LogParameters lower{};
  LogParameters upper{};
  std::array<double, kP> envelope{};  // largest coefficient each term may take alone
};

// Non-negative least squares of the relative AVAR residuals,
//   min Σ_j (1/s_j²) ((σ̂²_j − Σ_k c_k φ_k(τ_j))/σ̂²_j)²,  c ≥ 0,
// by trying every active set (at most 2⁵): the optimum satisfies the KKT
// conditions of one of them. Returns the cost; `c` gets the coefficients.
double NonNegativeFit(const FitData& data, const std::vector<int>& terms, double markov_tau_s,
                      std::array<double, kP>& c) {
  const auto n = static_cast<Eigen::Index>(data.tau.size());
  const auto p = static_cast<int>(terms.size());
  Eigen::MatrixXd A(n, p);
  Eigen::VectorXd b(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    const auto jj = static_cast<size_t>(j);
    const double w = 1.0 / data.sd[jj];
    b[j] = w;
    for (int k = 0; k < p; ++k) A(j, k) = w * Basis(terms[static_cast<size_t>(k)], data.tau[jj], markov_tau_s) / data.avar[jj];
  }
  double best = b.squaredNorm();
  c.fill(0.0);
  for (int set = 1; set < (1 << p); ++set) {
    std::vector<int> cols;
    for (int k = 0; k < p; ++k) {
      if (set & (1 << k)) cols.push_back(k);
    }
    Eigen::MatrixXd As(n, static_cast<Eigen::Index>(cols.size()));
    Eigen::VectorXd scale(static_cast<Eigen::Index>(cols.size()));
    for (size_t k = 0; k < cols.size(); ++k) {
      const auto kk = static_cast<Eigen::Index>(k);
      As.col(kk) = A.col(cols[k]);
      scale[kk] = As.col(kk).norm();
      if (!(scale[kk] > 0.0)) scale[kk] = 1.0;
      As.col(kk) /= scale[kk];
    }
    const Eigen::VectorXd x = As.colPivHouseholderQr().solve(b);
    if (!x.allFinite() || (x.array() <= 0.0).any()) continue;
    const double cost = (As * x - b).squaredNorm();
    if (cost < best) {
      best = cost;
      c.fill(0.0);
      for (size_t k = 0; k < cols.size(); ++k) {
        c[static_cast<size_t>(terms[static_cast<size_t>(cols[k])])] = x[static_cast<Eigen::Index>(k)] / scale[static_cast<Eigen::Index>(k)];
      }
    }
  }
  return best;
}

// Largest coefficient of term k the curve allows on its own.
double Envelope(const FitData& data, int k, double markov_tau_s) {
  double env = std::numeric_limits<double>::infinity();
  for (size_t j = 0; j < data.tau.size(); ++j) {
    const double phi = Basis(k, data.tau[j], markov_tau_s);
    if (phi > 0.0) env = std::min(env, data.avar[j] / phi);
  }
  return env;
}

// The Markov term is told from N (τ ≫ T) and K (τ ≪ T) only by its peak at
// τ ≈ u*·T, so T is confined to put the peak between 3τ_min and τ_max; a
// solution on these bounds is not resolved.
double MarkovTauMin(const FitData& data) { return 3.0 * data.tau.front() / MarkovShapePeak().u; }
double MarkovTauMax(const FitData& data) { return data.tau.back() / MarkovShapePeak().u; }

struct Start {
  LogParameters a{};
  Bounds bounds;
};

// Starting values and bounds for the candidate set `on` (NNLS, with a
// half-decade grid over T for the Markov term).
Start StartingValues(const FitData& data, const TermMask& on) {
  const double tau_min = data.tau.front();
  const double tau_max = data.tau.back();
  std::vector<int> linear;
  for (int k = 0; k < kMs; ++k) {
    if (on[static_cast<size_t>(k)]) linear.push_back(k);
  }
  std::array<double, kP> c{};
  double markov_tau = std::sqrt(tau_min * tau_max);
  if (on[kMs]) {
    std::vector<int> with_markov = linear;
    with_markov.push_back(kMs);
    double best = std::numeric_limits<double>::infinity();
    for (double t = MarkovTauMin(data); t <= MarkovTauMax(data); t *= std::sqrt(10.0)) {
      std::array<double, kP> ct{};
      const double cost = NonNegativeFit(data, with_markov, t, ct);
      if (cost < best) {
        best = cost;
        c = ct;
        markov_tau = t;
      }
    }
  } else {
    NonNegativeFit(data, linear, markov_tau, c);
  }

  const double avar_max = *std::max_element(data.avar.begin(), data.avar.end());
  const double avar_min = *std::min_element(data.avar.begin(), data.avar.end());
  Start s;
  for (int k = 0; k < kP; ++k) {
    const auto kk = static_cast<size_t>(k);
    double env = 0.0;
    if (k == kMt) {
      s.bounds.lower[kk] = std::log(MarkovTauMin(data));
      s.bounds.upper[kk] = std::log(MarkovTauMax(data));
      s.a[kk] = std::clamp(std::log(markov_tau), s.bounds.lower[kk] + 0.1, s.bounds.upper[kk] - 0.1);
      continue;
    }
    if (k == kMs) {
      s.bounds.lower[kk] = std::log(avar_min) - 40.0;
      s.bounds.upper[kk] = std::log(avar_max) + std::log(100.0 * tau_max / tau_min) + 5.0;
      env = Envelope(data, kMs, markov_tau);
    } else {
      env = Envelope(data, k, markov_tau);
      s.bounds.envelope[kk] = env;
      s.bounds.lower[kk] = std::log(env) - 40.0;
      s.bounds.upper[kk] = std::log(env) + 5.0;
    }
    const double start = c[kk] > 0.0 ? c[kk] : 1e-3 * env;
    s.a[kk] = std::clamp(std::log(start), s.bounds.lower[kk] + 1.0, s.bounds.upper[kk] - 1.0);
  }
  return s;
}

struct SolveOutcome {
  double cost = 0.0;  // Σ r²
  // Ceres ran out of iterations before any of its tolerances was met.
  bool stopped_at_iteration_cap = false;
};

// Weighted least squares in Ceres.
SolveOutcome Solve(const FitData& data, const TermMask& on, const Bounds& bounds,
                   int max_iterations, LogParameters& a) {
  ceres::Problem problem;
  for (size_t j = 0; j < data.tau.size(); ++j) {
    problem.AddResidualBlock(AllanLogResidual::Create(data.tau[j], data.y[j], 1.0 / data.sd[j], on), nullptr,
                             a.data());
  }
  // Terms outside `on` have zero Jacobian columns and stay where they are.
  for (int k = 0; k < kP; ++k) {
    const auto kk = static_cast<size_t>(k);
    a[kk] = std::clamp(a[kk], bounds.lower[kk], bounds.upper[kk]);
    problem.SetParameterLowerBound(a.data(), k, bounds.lower[kk]);
    problem.SetParameterUpperBound(a.data(), k, bounds.upper[kk]);
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = max_iterations;
  options.function_tolerance = 1e-12;
  options.gradient_tolerance = 1e-14;
  options.parameter_tolerance = 1e-12;
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  const LogParameters start = a;
  ceres::Solver::Summary summary;
  numerics::QuietSolverLog();
  ceres::Solve(options, &problem, &summary);
  const bool capped = summary.termination_type == ceres::NO_CONVERGENCE;
  if (summary.IsSolutionUsable()) return {2.0 * summary.final_cost, capped};
  // A failed solve (a numerical failure, not a slow one) may leave anything
  // in `a`: the fit stays at its start, with the cost of the start, so that
  // model selection compares a cost with the parameters it belongs to.
  a = start;
  double cost = std::numeric_limits<double>::infinity();
  problem.Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr, nullptr, nullptr);
  return {2.0 * cost, capped};
}

// Largest element (Eigen's maxCoeff trips GCC's -Wnull-dereference on dynamic vectors).
double LargestOf(const Eigen::VectorXd& v) {
  double m = -std::numeric_limits<double>::infinity();
  for (Eigen::Index k = 0; k < v.size(); ++k) m = std::max(m, v[k]);
  return m;
}

// ∂ ln σ²(τ_j)/∂a_k for the parameters in `on` (columns in parameter order).
Eigen::MatrixXd LogJacobian(const FitData& data, const LogParameters& a, const TermMask& on) {
  using Jet = ceres::Jet<double, kP>;
  std::array<Jet, kP> aj;
  for (int k = 0; k < kP; ++k) aj[static_cast<size_t>(k)] = Jet(a[static_cast<size_t>(k)], k);
  const int p = ParameterCount(on);
  Eigen::MatrixXd J(static_cast<Eigen::Index>(data.tau.size()), p);
  for (size_t j = 0; j < data.tau.size(); ++j) {
    const Jet f = ceres::log(ModelAvar(aj.data(), on, data.tau[j]));
    int col = 0;
    for (int k = 0; k < kP; ++k) {
      if (on[static_cast<size_t>(k)]) J(static_cast<Eigen::Index>(j), col++) = f.v[k];
    }
  }
  return J;
}

// Sandwich covariance of the log parameters in `on` (parameter order);
// directions the curve does not determine get infinite variance.
Eigen::MatrixXd SandwichCovariance(const FitData& data, const LogParameters& a, const TermMask& on,
                                   const Eigen::MatrixXd& V) {
  const Eigen::MatrixXd J = LogJacobian(data, a, on);
  Eigen::VectorXd w(J.rows());
  for (Eigen::Index j = 0; j < J.rows(); ++j) w[j] = 1.0 / (data.sd[static_cast<size_t>(j)] * data.sd[static_cast<size_t>(j)]);
  const Eigen::MatrixXd WJ = w.asDiagonal() * J;
  const Eigen::MatrixXd H = J.transpose() * WJ;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(H);
  const Eigen::VectorXd lambda = eig.eigenvalues();
  const double lmax = LargestOf(lambda);
  Eigen::VectorXd inv = Eigen::VectorXd::Zero(lambda.size());
  std::vector<bool> undetermined(static_cast<size_t>(H.rows()), false);
  for (Eigen::Index k = 0; k < lambda.size(); ++k) {
    if (lambda[k] > 1e-12 * lmax) {
      inv[k] = 1.0 / lambda[k];
    } else {
      for (Eigen::Index r = 0; r < H.rows(); ++r) {
        if (std::abs(eig.eigenvectors()(r, k)) > 1e-6) undetermined[static_cast<size_t>(r)] = true;
      }
    }
  }
  const Eigen::MatrixXd Hinv = eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose();
  Eigen::MatrixXd cov = Hinv * (WJ.transpose() * V * WJ) * Hinv;
  for (size_t r = 0; r < undetermined.size(); ++r) {
    if (undetermined[r]) cov(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(r)) = std::numeric_limits<double>::infinity();
  }
  return cov;
}

// Wald z of each parameter in `on` (indexed by parameter; 0 outside `on`).
std::array<double, kP> WaldZ(const Eigen::MatrixXd& cov, const TermMask& on) {
  std::array<double, kP> z{};
  int col = 0;
  for (int k = 0; k < kP; ++k) {
    if (!on[static_cast<size_t>(k)]) continue;
    const double var = cov(col, col);
    z[static_cast<size_t>(k)] = var > 0.0 && std::isfinite(var) ? 1.0 / std::sqrt(var) : 0.0;
    ++col;
  }
  return z;
}

Eigen::MatrixXd WithDiscrepancy(const Eigen::MatrixXd& V, double d2) {
  Eigen::MatrixXd out = V;
  out.diagonal().array() += d2;
  return out;
}

struct StructureFit {
  TermMask on{};
  LogParameters a{};
  Bounds bounds;
  double cost = 0.0;
  bool stopped_at_iteration_cap = false;        // of the solve that gave `a`
  std::vector<std::pair<int, double>> dropped;  // term, z when dropped
};

// Fits `fit`'s terms again from `fit.a`.
void Refit(const FitData& data, const Bounds& bounds, int max_iterations, StructureFit& fit) {
  const SolveOutcome outcome = Solve(data, fit.on, bounds, max_iterations, fit.a);
  fit.cost = outcome.cost;
  fit.stopped_at_iteration_cap = outcome.stopped_at_iteration_cap;
}

// Fits the candidate set and drops insignificant terms one at a time.
// `V` is the working covariance of ln σ̂² (with δ²I); empty: computed from
// the full candidate fit and returned (without δ²I) in `V_model`.
StructureFit FitStructure(const FitData& data, const TermMask& candidates, double tau0,
                          std::span<const size_t> segment_samples, const AllanOptions& options,
                          Eigen::MatrixXd& V_model) {
  StructureFit fit;
  fit.on = candidates;
  const Start start = StartingValues(data, candidates);
  fit.a = start.a;
  fit.bounds = start.bounds;
  Refit(data, start.bounds, options.max_solver_iterations, fit);
  if (V_model.size() == 0) V_model = LogAvarCovariance(data, fit.a, fit.on, tau0, segment_samples);
  const Eigen::MatrixXd V = WithDiscrepancy(V_model, data.discrepancy2);
  while (TermCount(fit.on) > 1) {
    std::array<double, kP> z = WaldZ(SandwichCovariance(data, fit.a, fit.on, V), fit.on);
    if (fit.on[kMt] && (fit.a[kMt] <= start.bounds.lower[kMt] + 1e-3 || fit.a[kMt] >= start.bounds.upper[kMt] - 1e-3)) {
      z[kMt] = 0.0;  // T on a bound: the peak is outside the curve
    }
    int worst = -1;
    double worst_z = std::numeric_limits<double>::infinity();
    for (int k = 0; k < kMt; ++k) {
      if (!fit.on[static_cast<size_t>(k)]) continue;
      const double zk = k == kMs ? std::min(z[kMs], z[kMt]) : z[static_cast<size_t>(k)];
      if (zk < worst_z) {
        worst_z = zk;
        worst = k;
      }
    }
    if (worst < 0 || worst_z >= options.significance_z) break;
    fit.dropped.emplace_back(worst, worst_z);
    fit.on[static_cast<size_t>(worst)] = false;
    if (worst == kMs) fit.on[kMt] = false;
    Refit(data, start.bounds, options.max_solver_iterations, fit);
  }
  return fit;
}

// The curve's points as the fit sees them: y = ln σ̂² corrected for the mean
// of ln χ²_ν/ν, with the standard deviation of ln χ²_ν.
FitData DataOfCurve(const std::vector<AllanPoint>& curve) {
  FitData data;
  for (size_t j = 0; j < curve.size(); ++j) {
    const AllanPoint& p = curve[j];
    if (!(p.adev > 0.0) || !(p.edf >= 1.0)) continue;
    data.point.push_back(j);
    data.m.push_back(p.m);
    data.tau.push_back(p.tau_s);
    data.avar.push_back(p.adev * p.adev);
    data.y.push_back(std::log(p.adev * p.adev) - stats::LogChiSquareMeanOffset(p.edf));
    data.s.push_back(std::sqrt(stats::LogChiSquareVariance(p.edf)));
  }
  return data;
}

// The candidate sets: the random terms with the Markov term, with flicker
// (B) instead, with both (a unit whose drift has a bump above its floor), and
// every term. The deterministic ramp is tested last, against the random terms.
struct CandidateSets {
  TermMask markov{}, flicker{}, both{}, all{};
};
CandidateSets CandidatesOf(const AllanOptions::Terms& cand) {
  CandidateSets sets;
  sets.markov[kQ] = cand.quantization;
  sets.markov[kN] = cand.white;
  sets.markov[kK] = cand.rate_random_walk;
  sets.markov[kMs] = sets.markov[kMt] = cand.markov;
  sets.flicker = sets.markov;
  sets.flicker[kMs] = sets.flicker[kMt] = false;
  sets.flicker[kB] = cand.bias_instability;
  sets.both = sets.markov;
  sets.both[kB] = cand.bias_instability;
  sets.all = sets.both;
  sets.all[kR] = cand.rate_ramp;
  return sets;
}

// The terms chosen for the curve, and what was tried.
struct Selection {
  StructureFit fit;
  bool markov = false;
  TermMask candidates{};
  Eigen::MatrixXd V_model;  // V of the selected model (no δ²)
  std::vector<std::string> unresolved_extra;
};

// What the fit needs besides the curve.
struct FitContext {
  double tau0_s;
  std::span<const size_t> segment_samples;
  const AllanOptions& options;
};

// Ramp test: R's Wald z under the covariance of the model without it (the
// null hypothesis), since a deterministic ramp's own model claims the
// large-τ estimates are nearly exact.
void TestRamp(const FitData& data, const FitContext& c, Selection& sel) {
  sel.candidates[kR] = true;
  StructureFit ramp = sel.fit;
  ramp.on[kR] = true;
  double best = std::numeric_limits<double>::infinity();
  for (double fraction : {1e-1, 1e-4}) {
    LogParameters a = sel.fit.a;
    a[kR] = std::log(fraction * ramp.bounds.envelope[kR]);
    const SolveOutcome outcome =
        Solve(data, ramp.on, ramp.bounds, c.options.max_solver_iterations, a);
    if (outcome.cost < best) {
      best = outcome.cost;
      ramp.a = a;
      ramp.cost = outcome.cost;
      ramp.stopped_at_iteration_cap = outcome.stopped_at_iteration_cap;
    }
  }
  const Eigen::MatrixXd V0 = WithDiscrepancy(sel.V_model, data.discrepancy2);
  const double z = WaldZ(SandwichCovariance(data, ramp.a, ramp.on, V0), ramp.on)[kR];
  if (z >= c.options.significance_z) {
    sel.fit = ramp;
    sel.V_model = LogAvarCovariance(data, sel.fit.a, sel.fit.on, c.tau0_s, c.segment_samples);
  } else {
    sel.fit.dropped.emplace_back(kR, z);
  }
}

Eigen::VectorXd Residuals(const FitData& data, const StructureFit& f);

// eᵀV⁻¹e over the directions V resolves (eigenvalues above 1e-9 of the
// largest), and their number.
std::pair<double, int> ResolvedChi2(const Eigen::MatrixXd& V, const Eigen::VectorXd& e) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(V);
  const double lmax = LargestOf(eig.eigenvalues());
  double chi2 = 0.0;
  int rank = 0;
  for (Eigen::Index k = 0; k < e.size(); ++k) {
    const double l = eig.eigenvalues()[k];
    if (!(l > 1e-9 * lmax)) continue;
    const double proj = eig.eigenvectors().col(k).dot(e);
    chi2 += proj * proj / l;
    ++rank;
  }
  return {chi2, rank};
}

// Akaike's criterion of a structure's fit to the curve, its generalised χ²
// under V (with the curve's discrepancy δ²) plus twice its terms (Akaike,
// IEEE Trans. Autom. Control 19(6), 1974).
double StructureAic(const FitData& data, const StructureFit& f, const Eigen::MatrixXd& V) {
  return ResolvedChi2(WithDiscrepancy(V, data.discrepancy2), Residuals(data, f)).first + 2.0 * ParameterCount(f.on);
}

// Chooses the terms: the structure the curve prefers of those that resolve
// their terms (below); then the ramp. One working covariance `V_work` (of the full
// Markov candidate fit) serves the eliminations of both structures: they
// describe the same curve, and it only has to reflect the estimator's noise.
Selection SelectTerms(const FitData& data, const CandidateSets& sets, const FitContext& c, Eigen::MatrixXd& V_work) {
  const AllanOptions& options = c.options;
  Selection sel;
  if (!options.select_terms) {
    // Every candidate, fitted once.
    sel.fit.on = sets.all;
    const Start start = StartingValues(data, sets.all);
    sel.fit.a = start.a;
    sel.fit.bounds = start.bounds;
    Refit(data, start.bounds, options.max_solver_iterations, sel.fit);
    sel.markov = sets.all[kMs];
    sel.candidates = sets.all;
    sel.V_model = LogAvarCovariance(data, sel.fit.a, sel.fit.on, c.tau0_s, c.segment_samples);
    return sel;
  }
  // Each structure fitted and its unresolved terms eliminated; of those that
  // keep what makes them differ (σ_m and T; B; all three), the one of least
  // Akaike criterion, by the generalised χ² under the one working covariance
  // (with δ²) plus twice its terms (Akaike, IEEE Trans. Autom. Control 19(6),
  // 1974). Where none does, the flicker set as eliminated.
  struct Tried {
    StructureFit fit;
    TermMask candidates;
    bool resolved = false;
  };
  std::vector<Tried> tried;
  auto any = [](const TermMask& m) { return std::any_of(m.begin(), m.end(), [](bool b) { return b; }); };
  if (options.candidates.markov) {
    StructureFit f = FitStructure(data, sets.markov, c.tau0_s, c.segment_samples, options, V_work);
    tried.push_back({f, sets.markov, f.on[kMs]});
  }
  if (any(sets.flicker)) {
    StructureFit f = FitStructure(data, sets.flicker, c.tau0_s, c.segment_samples, options, V_work);
    tried.push_back({f, sets.flicker, f.on[kB]});
  }
  if (options.candidates.markov && options.candidates.bias_instability) {
    StructureFit f = FitStructure(data, sets.both, c.tau0_s, c.segment_samples, options, V_work);
    tried.push_back({f, sets.both, f.on[kMs] && f.on[kB]});
  }
  const Tried* chosen = nullptr;
  double best_aic = std::numeric_limits<double>::infinity();
  for (const Tried& t : tried) {
    if (!t.resolved) continue;
    const double aic = StructureAic(data, t.fit, V_work);
    if (aic < best_aic) {
      best_aic = aic;
      chosen = &t;
    }
  }
  for (const Tried& t : tried) {
    if (chosen == nullptr && t.candidates == sets.flicker) chosen = &t;
  }
  if (chosen == nullptr && !tried.empty()) chosen = &tried.front();
  if (chosen != nullptr) {
    sel.fit = chosen->fit;
    sel.markov = chosen->fit.on[kMs];
    sel.candidates = chosen->candidates;
    if (!sel.markov && options.candidates.markov) {
      for (const auto& [k, z] : tried.front().fit.dropped) {
        if (k == kMs) sel.unresolved_extra.push_back("markov (z = " + FormatG(z, 2) + ")");
      }
    }
  }
  sel.V_model = LogAvarCovariance(data, sel.fit.a, sel.fit.on, c.tau0_s, c.segment_samples);
  if (options.candidates.rate_ramp) TestRamp(data, c, sel);
  return sel;
}

Eigen::VectorXd Residuals(const FitData& data, const StructureFit& f) {
  const auto n = static_cast<Eigen::Index>(data.tau.size());
  Eigen::VectorXd e(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    const auto jj = static_cast<size_t>(j);
    e[j] = data.y[jj] - std::log(ModelAvar(f.a.data(), f.on, data.tau[jj]));
  }
  return e;
}

// The adequacy test: χ²_g = eᵀV⁻¹e over the directions V resolves
// (eigenvalues above 1e-9 of the largest).
void TestAdequacy(const Selection& sel, const Eigen::VectorXd& e, const AllanOptions& options, AllanFit& out) {
  const auto [chi2, rank] = ResolvedChi2(sel.V_model, e);
  out.generalized_chi2 = chi2;
  out.dof = std::max(1, rank - ParameterCount(sel.fit.on));
  out.p_value = stats::ChiSquareSurvival(chi2, out.dof);
  out.adequate = out.p_value >= options.adequacy_alpha;
}

// Model discrepancy: δ² with eᵀ(V + δ²I)⁻¹e = n − p (a random-effects
// variance: the share of ln σ̂² the model cannot explain). The weights become
// 1/(s² + δ²), so the most precise points no longer pull the fit alone, and
// the terms are selected again. Two rounds.
void FitWithDiscrepancy(FitData& data, const CandidateSets& sets, const FitContext& c, Eigen::MatrixXd& V_work,
                        Selection& sel, Eigen::VectorXd& e) {
  const auto n = static_cast<Eigen::Index>(data.tau.size());
  for (int round = 0; round < 2; ++round) {
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(sel.V_model);
    const Eigen::VectorXd proj = eig.eigenvectors().transpose() * e;
    const double target = std::max(1.0, static_cast<double>(n - ParameterCount(sel.fit.on)));
    auto chi2_at = [&](double d2) {
      double chi2 = 0.0;
      for (Eigen::Index k = 0; k < n; ++k) chi2 += proj[k] * proj[k] / (std::max(0.0, eig.eigenvalues()[k]) + d2);
      return chi2;
    };
    double lo = std::log(1e-12);
    double hi = std::log(1e2);
    for (int i = 0; i < 100; ++i) {
      const double mid = 0.5 * (lo + hi);
      (chi2_at(std::exp(mid)) > target ? lo : hi) = mid;
    }
    data.SetDiscrepancy(std::exp(0.5 * (lo + hi)));
    if (round == 0) {
      sel = SelectTerms(data, sets, c, V_work);
    } else {
      const Start start = StartingValues(data, sel.fit.on);
      Refit(data, start.bounds, c.options.max_solver_iterations, sel.fit);
      sel.V_model = LogAvarCovariance(data, sel.fit.a, sel.fit.on, c.tau0_s, c.segment_samples);
    }
    e = Residuals(data, sel.fit);
  }
}

// Each term's estimate and SE from the sandwich covariance `cov` of the
// chosen terms' log coefficients, and the terms left out.
void FillEstimates(const Selection& sel, const Eigen::MatrixXd& cov, AllanFit& out) {
  const StructureFit& chosen = sel.fit;
  const AllanNoiseTerms terms = TermsFromLog(chosen.a, chosen.on);
  const double values[kP] = {terms.quantization,     terms.white_density, terms.bias_instability,
                             terms.rate_random_walk, terms.rate_ramp,     terms.markov_sigma,
                             terms.markov_tau_s};
  int col = 0;
  for (int k = 0; k < kP; ++k) {
    AllanTermEstimate& t = out.parameters[static_cast<size_t>(k)];
    t.tried = sel.candidates[static_cast<size_t>(k)];
    if (!chosen.on[static_cast<size_t>(k)]) continue;
    const double var = cov(col, col);
    ++col;
    t.included = true;
    t.value = values[k];
    const double se_log = var >= 0.0 ? std::sqrt(var) : std::numeric_limits<double>::infinity();
    t.z = se_log > 0.0 ? 1.0 / se_log : std::numeric_limits<double>::infinity();
    // Amplitudes are square roots of their AVAR coefficient: SE = v·SE(a)/2; T = e^a.
    t.std_error = t.value * se_log * (k == kMt ? 1.0 : 0.5);
  }
  for (const auto& [k, z] : chosen.dropped) {
    out.unresolved.push_back(std::string(AllanParameterName(static_cast<AllanParameter>(k))) + " (z = " +
                             FormatG(z, 2) + ")");
  }
  for (const std::string& u : sel.unresolved_extra) out.unresolved.push_back(u);
}

// What an inadequate fit's note says: the test, the discrepancy added, and
// the τ ranges whose points depart beyond 3σ.
std::string InadequacyNote(const std::vector<AllanPoint>& curve, const std::vector<bool>& disagree,
                           const AllanFit& out) {
  std::string ranges;
  for (size_t j = 0; j < curve.size();) {
    if (!disagree[j]) {
      ++j;
      continue;
    }
    size_t end = j;
    while (end + 1 < curve.size() && disagree[end + 1]) ++end;
    ranges += (ranges.empty() ? "" : ", ") + FormatG(curve[j].tau_s) + "–" + FormatG(curve[end].tau_s) + " s";
    j = end + 1;
  }
  return "the noise model does not explain the curve (χ² = " + FormatG(out.generalized_chi2) + " on " +
         std::to_string(out.dof) + " dof, p = " + FormatG(out.p_value, 2) +
         "): fitted again with a model discrepancy of " + FormatG(100.0 * out.discrepancy, 2) +
         "% in σ² added to every point" +
         (ranges.empty() ? std::string() : "; departures beyond 3σ at τ = " + ranges);
}

}  // namespace

absl::StatusOr<AllanFit> FitAllanCurve(std::vector<AllanPoint>& curve, double tau0_s,
                                       std::span<const size_t> segment_samples, const AllanOptions& options) {
  if (auto st = options.Validate(); !st.ok()) return st;
  FitData data = DataOfCurve(curve);
  if (data.tau.size() < 2) {
    return absl::FailedPreconditionError("Allan fit: fewer than two points with a positive Allan deviation");
  }
  data.SetDiscrepancy(0.0);
  const CandidateSets sets = CandidatesOf(options.candidates);
  if (std::none_of(sets.all.begin(), sets.all.end(), [](bool b) { return b; })) {
    return absl::InvalidArgumentError("Allan fit: no candidate term");
  }
  const FitContext context{tau0_s, segment_samples, options};
  Eigen::MatrixXd V_work;
  Selection sel = SelectTerms(data, sets, context, V_work);
  Eigen::VectorXd e = Residuals(data, sel.fit);
  AllanFit out;
  out.points = static_cast<int>(data.tau.size());
  TestAdequacy(sel, e, options, out);
  if (!out.adequate) FitWithDiscrepancy(data, sets, context, V_work, sel, e);
  out.discrepancy = std::sqrt(data.discrepancy2);
  out.markov_structure = sel.markov;
  const Eigen::MatrixXd V = WithDiscrepancy(sel.V_model, data.discrepancy2);
  const Eigen::MatrixXd cov = SandwichCovariance(data, sel.fit.a, sel.fit.on, V);
  out.free_parameters = ParameterCount(sel.fit.on);
  out.weighted_sse = sel.fit.cost;

  // Per-point fit and standardised residuals.
  std::vector<bool> disagree(curve.size(), false);
  for (Eigen::Index j = 0; j < e.size(); ++j) {
    const auto jj = static_cast<size_t>(j);
    AllanPoint& p = curve[data.point[jj]];
    p.fitted_adev = std::sqrt(ModelAvar(sel.fit.a.data(), sel.fit.on, data.tau[jj]));
    p.log_residual = e[j] / std::sqrt(sel.V_model(j, j));
    disagree[data.point[jj]] = std::abs(p.log_residual) > 3.0;
  }
  FillEstimates(sel, cov, out);
  if (!out.adequate) out.notes.push_back(InadequacyNote(curve, disagree, out));
  if (sel.fit.stopped_at_iteration_cap) {
    out.notes.push_back("the least-squares fit stopped at its iteration cap (" +
                        std::to_string(options.max_solver_iterations) +
                        ") before converging: its estimates may not be at the optimum");
  }
  return out;
}

}  // namespace insdiag::engine::ident
