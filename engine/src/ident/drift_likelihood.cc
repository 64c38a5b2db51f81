#include "insdiag/engine/ident/drift_likelihood.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <Eigen/Core>
#include <Eigen/LU>

#include "insdiag/engine/filter/smoother.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/model/state_layout.h"

namespace insdiag::engine::ident {
namespace {

int WalkEffectOf(const ErrorModel& m, int drift) {
  auto terms = ParseEffectSelector(WalkName(drift));
  return terms.ok() ? m.FindEffect(terms->front()) : -1;
}

// One parameter of the likelihood: a drift's σ or τ, or a walk's density K.
enum class Kind { kSigma, kTau, kWalk };
struct Parameter {
  Kind kind = Kind::kSigma;
  int drift = 0;
};

// The parameter's value in a model: a reference into it (const for a const model).
template <typename Model>
auto& ValueOf(Model& m, const Parameter& p) {
  switch (p.kind) {
    case Kind::kSigma:
      return DriftOf(m, p.drift).sigma;
    case Kind::kTau:
      return DriftOf(m, p.drift).tau_s;
    case Kind::kWalk:
      break;
  }
  return m.effects[static_cast<size_t>(WalkEffectOf(m, p.drift))].random_walk_density;
}

std::string NameOf(const Parameter& p) {
  switch (p.kind) {
    case Kind::kSigma:
      return DriftName(p.drift) + ".sigma";
    case Kind::kTau:
      return DriftName(p.drift) + ".tau";
    case Kind::kWalk:
      break;
  }
  return WalkName(p.drift) + ".density";
}

const char* UnitOf(const Parameter& p) {
  switch (p.kind) {
    case Kind::kSigma:
      return p.drift < 3 ? "rad/s" : "m/s^2";
    case Kind::kTau:
      return "s";
    case Kind::kWalk:
      break;
  }
  return p.drift < 3 ? "rad/s/sqrt(s)" : "m/s^2/sqrt(s)";
}

// EM over θ = ln of each parameter (header), with the pass count of `out`.
class Maximiser {
 public:
  Maximiser(const BenchRun& run, ErrorModel model, std::vector<Parameter> parameters, const FilterOptions& filter,
            const DriftLikelihoodOptions& options, DriftLikelihoodResult& out)
      : run_(run), model_(std::move(model)), layout_(model_), parameters_(std::move(parameters)), filter_(filter),
        options_(options), out_(out) {
    for (const Parameter& p : parameters_) {
      if (p.kind == Kind::kTau) tau_free_[static_cast<size_t>(p.drift)] = true;
    }
  }

  Eigen::VectorXd Start() const {
    Eigen::VectorXd theta(static_cast<Eigen::Index>(parameters_.size()));
    for (size_t j = 0; j < parameters_.size(); ++j) theta[static_cast<Eigen::Index>(j)] = std::log(ValueOf(model_, parameters_[j]));
    return theta;
  }

  ErrorModel ModelOf(const Eigen::VectorXd& theta) const {
    ErrorModel m = model_;
    for (size_t j = 0; j < parameters_.size(); ++j) ValueOf(m, parameters_[j]) = std::exp(theta[static_cast<Eigen::Index>(j)]);
    return m;
  }

  absl::StatusOr<double> LogLikelihood(const ErrorModel& m) {
    ++out_.filter_passes;
    auto fw = RunForwardFilter(run_, m, filter_);
    if (!fw.ok()) return fw.status();
    return fw->log_likelihood;
  }

  // ℓ(θ) and the M-step's θ.
  struct Step {
    double log_likelihood;
    Eigen::VectorXd next;
  };
  absl::StatusOr<Step> EmStep(const Eigen::VectorXd& theta) {
    ++out_.filter_passes;
    auto fw = RunForwardFilter(run_, ModelOf(theta), filter_);
    if (!fw.ok()) return fw.status();
    const int K = fw->epochs();
    if (K < 3) return absl::InvalidArgumentError("drift likelihood: the run has fewer than three epochs");
    auto sm = RunSmoother(*fw);
    if (!sm.ok()) return sm.status();
    const double dt = (fw->epoch_time_s.back() - fw->epoch_time_s.front()) / (K - 1);
    Step step{fw->log_likelihood, theta};
    for (size_t j = 0; j < parameters_.size(); ++j) {
      const Parameter& p = parameters_[j];
      const bool walk = p.kind == Kind::kWalk;
      const int state = walk ? layout_.EffectOffset(WalkEffectOf(model_, p.drift)) : layout_.gyro_bias() + p.drift;
      double a_from = 0.0, a_to = 0.0, b = 0.0;
      for (int k = 0; k + 1 < K; ++k) {
        const double x0 = sm->x(k, state), x1 = sm->x(k + 1, state);
        a_from += x0 * x0 + sm->variance(k, state);
        a_to += x1 * x1 + sm->variance(k + 1, state);
        b += x1 * x0 + sm->lag_one_covariance(k, state);
      }
      const double a0 = sm->x(0, state) * sm->x(0, state) + sm->variance(0, state);
      const auto i = static_cast<Eigen::Index>(j);
      if (walk) {
        const double k2 = (a_to - 2.0 * b + a_from) / ((K - 1) * dt);  // K̂²
        if (k2 > 0.0) step.next[i] = 0.5 * std::log(k2);
      } else if (tau_free_[static_cast<size_t>(p.drift)]) {
        // σ and τ together: the AR(1) regression of the header, φ̂ = Σb / Σa,
        // q̂ = Σ E[(x_{k+1} − φ̂ x_k)²] / (n − 1), σ̂² = q̂ / (1 − φ̂²) (the
        // initial state's term, one of n, left out of the φ step).
        const double phi = b / a_from;
        if (!(phi > 0.0 && phi < 1.0)) continue;
        const double q = (a_to - 2.0 * phi * b + phi * phi * a_from) / (K - 1);
        if (p.kind == Kind::kTau) {
          step.next[i] = std::log(-dt / std::log(phi));
        } else if (q > 0.0) {
          step.next[i] = 0.5 * std::log(q / (1.0 - phi * phi));
        }
      } else {
        const double phi = std::exp(-dt / DriftOf(model_, p.drift).tau_s);
        const double sigma2 = (a0 + (a_to - 2.0 * phi * b + phi * phi * a_from) / (1.0 - phi * phi)) / K;  // σ̂²
        if (sigma2 > 0.0) step.next[i] = 0.5 * std::log(sigma2);
      }
    }
    return step;
  }

  // SQUAREM, scheme S3 (Varadhan & Roland 2008): two EM steps give
  // r = θ₁ − θ₀ and v = θ₂ − 2θ₁ + θ₀; with α = −‖r‖/‖v‖ (at most −1, which
  // is θ₂ itself) θ′ = θ₀ − 2αr + α²v, whose EM step continues the cycle when
  // its likelihood is not below θ₂'s. A step length per parameter: they are
  // near-independent, and one that crawls must not wait for the others.
  // Returns the maximiser; `first_likelihood` gets ℓ at the start.
  absl::StatusOr<Eigen::VectorXd> Maximise(Eigen::VectorXd theta, double* first_likelihood) {
    const Eigen::Index m = theta.size();
    for (int cycle = 0, iterations = 0; iterations < options_.max_iterations; ++cycle) {
      auto first = EmStep(theta);
      if (!first.ok()) return first.status();
      if (cycle == 0 && first_likelihood != nullptr) *first_likelihood = first->log_likelihood;
      auto second = EmStep(first->next);
      if (!second.ok()) return second.status();
      iterations += 2;
      const Eigen::VectorXd r = first->next - theta;
      const Eigen::VectorXd v = second->next - first->next - r;
      Eigen::VectorXd next = second->next;
      Eigen::VectorXd extrapolated = second->next;
      bool extrapolates = false;
      for (Eigen::Index j = 0; j < m; ++j) {
        if (!(std::abs(v[j]) > 0.0)) continue;
        const double alpha = std::min(-1.0, -std::abs(r[j]) / std::abs(v[j]));
        extrapolated[j] = theta[j] - 2.0 * alpha * r[j] + alpha * alpha * v[j];
        extrapolates = extrapolates || alpha < -1.0;
      }
      if (extrapolates) {
        auto third = EmStep(extrapolated);
        if (!third.ok()) return third.status();
        ++iterations;
        if (third->log_likelihood >= second->log_likelihood) next = third->next;
      }
      const double largest_step = (next - theta).cwiseAbs().maxCoeff();
      theta = next;
      if (largest_step < options_.log_tolerance) {
        converged_ = true;
        iterations_ = iterations;
        return theta;
      }
      iterations_ = iterations;
    }
    return theta;
  }

  // Observed information in θ_j at θ (ℓ(θ) = l0): the second difference.
  absl::StatusOr<double> Information(const Eigen::VectorXd& theta, Eigen::Index j, double l0) {
    const double h = options_.curvature_step;
    double shifted[2];
    for (int side = 0; side < 2; ++side) {
      Eigen::VectorXd probe = theta;
      probe[j] += side == 0 ? h : -h;
      auto l = LogLikelihood(ModelOf(probe));
      if (!l.ok()) return l.status();
      shifted[side] = *l;
    }
    return -(shifted[0] - 2.0 * l0 + shifted[1]) / (h * h);
  }

  // Observed information of the pair (θ_i, θ_j) at θ: second differences,
  // the mixed one from the two diagonal shifts (Abramowitz & Stegun 25.3.27).
  absl::StatusOr<Eigen::Matrix2d> PairInformation(const Eigen::VectorXd& theta, Eigen::Index i, Eigen::Index j,
                                                  double l0) {
    const double h = options_.curvature_step;
    auto at = [&](double di, double dj) -> absl::StatusOr<double> {
      Eigen::VectorXd probe = theta;
      probe[i] += di;
      probe[j] += dj;
      return LogLikelihood(ModelOf(probe));
    };
    double l[6];
    const double shifts[6][2] = {{h, 0}, {-h, 0}, {0, h}, {0, -h}, {h, h}, {-h, -h}};
    for (int k = 0; k < 6; ++k) {
      auto v = at(shifts[k][0], shifts[k][1]);
      if (!v.ok()) return v.status();
      l[k] = *v;
    }
    Eigen::Matrix2d information;
    information(0, 0) = -(l[0] - 2.0 * l0 + l[1]) / (h * h);
    information(1, 1) = -(l[2] - 2.0 * l0 + l[3]) / (h * h);
    information(0, 1) = information(1, 0) = -(l[4] + l[5] - l[0] - l[1] - l[2] - l[3] + 2.0 * l0) / (2.0 * h * h);
    return information;
  }

  const std::vector<Parameter>& parameters() const { return parameters_; }
  bool converged() const { return converged_; }
  int iterations() const { return iterations_; }

 private:
  const BenchRun& run_;
  ErrorModel model_;
  StateLayout layout_;
  std::vector<Parameter> parameters_;
  const FilterOptions& filter_;
  const DriftLikelihoodOptions& options_;
  DriftLikelihoodResult& out_;
  DriftSelection tau_free_{};  // drifts whose τ is a parameter too
  bool converged_ = false;
  int iterations_ = 0;
};

absl::Status ValidateOptions(const DriftLikelihoodOptions& options) {
  if (!(options.max_iterations > 0 && options.log_tolerance > 0.0 && options.curvature_step > 0.0)) {
    return absl::InvalidArgumentError("drift likelihood options out of range");
  }
  return absl::OkStatus();
}

bool HasDrift(const ErrorModel& m, int drift) { return DriftOf(m, drift).sigma > 0.0 && DriftOf(m, drift).tau_s > 0.0; }

// Maximises from the model's values into `out` (model, iterations,
// convergence, ℓ at the estimate); `first_likelihood` gets ℓ at the start.
absl::StatusOr<Eigen::VectorXd> FitInto(Maximiser& em, DriftLikelihoodResult& out, double* first_likelihood) {
  auto theta = em.Maximise(em.Start(), first_likelihood);
  if (!theta.ok()) return theta.status();
  out.iterations = em.iterations();
  out.converged = em.converged();
  out.model = em.ModelOf(*theta);
  auto l = em.LogLikelihood(out.model);
  if (!l.ok()) return l.status();
  out.log_likelihood_after = *l;
  return theta;
}

ParameterEstimate EstimateOf(const Parameter& p, double value, double log_se, const ErrorModel& a_priori) {
  ParameterEstimate e;
  e.name = NameOf(p);
  e.value = value;
  e.std_error = value * log_se;
  e.ci95_low = value * std::exp(-1.96 * log_se);
  e.ci95_high = value * std::exp(1.96 * log_se);
  e.method = "ML";
  e.unit = UnitOf(p);
  if (p.kind != Kind::kWalk) e.a_priori = ValueOf(a_priori, p);
  return e;
}

}  // namespace

GaussMarkov& DriftOf(ErrorModel& m, int drift) {
  return (drift < 3 ? m.gyro : m.acc).bias[static_cast<size_t>(drift % 3)];
}
const GaussMarkov& DriftOf(const ErrorModel& m, int drift) {
  return (drift < 3 ? m.gyro : m.acc).bias[static_cast<size_t>(drift % 3)];
}

std::string DriftName(int drift) {
  return std::string(drift < 3 ? "gyro_bias_gm." : "acc_bias_gm.") + "xyz"[drift % 3];
}

std::string WalkName(int drift) {
  return std::string(drift < 3 ? "gyro_bias_rw." : "acc_bias_rw.") + "xyz"[drift % 3];
}

absl::StatusOr<DriftLikelihoodResult> IdentifyDriftsByLikelihood(const BenchRun& run, const ErrorModel& model,
                                                                 const ErrorModel& a_priori,
                                                                 const DriftSelection& which,
                                                                 const DriftSelection& tau_too,
                                                                 const FilterOptions& filter,
                                                                 const DriftLikelihoodOptions& options) {
  if (auto st = ValidateOptions(options); !st.ok()) return st;
  DriftLikelihoodResult out;
  out.model = model;
  std::vector<Parameter> parameters;
  for (int d = 0; d < 6; ++d) {
    // A drift the model leaves out (σ = 0) has no state to identify.
    if (!which[static_cast<size_t>(d)] || !HasDrift(model, d)) continue;
    parameters.push_back({Kind::kSigma, d});
    if (tau_too[static_cast<size_t>(d)]) parameters.push_back({Kind::kTau, d});
  }
  if (parameters.empty()) {
    out.converged = true;
    return out;
  }
  Maximiser em(run, model, parameters, filter, options, out);
  auto theta = FitInto(em, out, &out.log_likelihood_before);
  if (!theta.ok()) return theta.status();
  const double l0 = out.log_likelihood_after;

  // The curvature at the estimate (observed information) in ln σ, or in
  // (ln σ, ln τ) jointly where τ is identified too: the two trade along a
  // ridge, and their errors must show it.
  bool any_flat = false;
  for (size_t j = 0; j < parameters.size(); ++j) {
    const Parameter& p = parameters[j];
    if (p.kind != Kind::kSigma) continue;
    const auto i = static_cast<Eigen::Index>(j);
    const bool with_tau = j + 1 < parameters.size() && parameters[j + 1].kind == Kind::kTau;
    std::vector<double> log_se;
    if (with_tau) {
      auto information = em.PairInformation(*theta, i, i + 1, l0);
      if (!information.ok()) return information.status();
      if ((*information)(0, 0) > 0.0 && information->determinant() > 0.0) {
        const Eigen::Matrix2d covariance = information->inverse();
        log_se = {std::sqrt(covariance(0, 0)), std::sqrt(covariance(1, 1))};
      }
    } else {
      auto information = em.Information(*theta, i, l0);
      if (!information.ok()) return information.status();
      if (*information > 0.0) log_se = {1.0 / std::sqrt(*information)};
    }
    const size_t count = with_tau ? 2 : 1;
    for (size_t k = 0; k < count; ++k) {
      const Parameter& q = parameters[j + k];
      if (log_se.empty()) {
        // The likelihood is flat here: the run's motion does not make the
        // drift observable (a level gyro's heading drift on a still table).
        // Not an estimate — the model keeps its value.
        ValueOf(out.model, q) = ValueOf(model, q);
        out.not_identifiable.push_back(NameOf(q));
        any_flat = true;
        continue;
      }
      out.identified.push_back(EstimateOf(q, std::exp((*theta)[i + static_cast<Eigen::Index>(k)]), log_se[k], a_priori));
    }
  }
  if (any_flat) {
    auto kept = em.LogLikelihood(out.model);
    if (!kept.ok()) return kept.status();
    out.log_likelihood_after = *kept;
  }
  return out;
}

absl::StatusOr<DriftLikelihoodResult> IdentifyWalksByLikelihood(const BenchRun& run, const ErrorModel& model,
                                                                const ErrorModel& a_priori,
                                                                const DriftSelection& axes,
                                                                const FilterOptions& filter,
                                                                const DriftLikelihoodOptions& options) {
  if (auto st = ValidateOptions(options); !st.ok()) return st;
  DriftLikelihoodResult out;
  out.model = model;
  out.converged = true;

  // Every candidate walk at the walk hypothesis (header): the drift at its
  // a-priori σ (not wider: a widened drift took the slow variance a walk
  // would explain) and the walk at that drift's short-term level σ√(2/τ).
  ErrorModel trial = model;
  std::vector<Parameter> parameters;
  for (int d = 0; d < 6; ++d) {
    if (!axes[static_cast<size_t>(d)] || !HasDrift(model, d) || WalkEffectOf(model, d) >= 0) continue;
    auto terms = ParseEffectSelector(WalkName(d));
    if (!terms.ok()) return terms.status();
    ModelEffect walk;
    walk.term = terms->front();
    const GaussMarkov& specified = HasDrift(a_priori, d) ? DriftOf(a_priori, d) : DriftOf(model, d);
    GaussMarkov& drift = DriftOf(trial, d);
    drift.sigma = std::min(drift.sigma, specified.sigma);
    walk.random_walk_density = drift.sigma * std::sqrt(2.0 / specified.tau_s);
    trial.effects.push_back(walk);
    parameters.push_back({Kind::kSigma, d});
    parameters.push_back({Kind::kWalk, d});
  }
  if (parameters.empty()) return out;

  // The screen: one EM step; a walk whose K falls is not told from the drift.
  std::vector<int> kept_axes;
  {
    Maximiser screen(run, trial, parameters, filter, options, out);
    const Eigen::VectorXd start = screen.Start();
    auto step = screen.EmStep(start);
    if (!step.ok()) return step.status();
    out.log_likelihood_before = step->log_likelihood;
    for (size_t j = 0; j < parameters.size(); ++j) {
      const auto i = static_cast<Eigen::Index>(j);
      if (parameters[j].kind == Kind::kWalk && step->next[i] > start[i]) kept_axes.push_back(parameters[j].drift);
    }
  }
  if (kept_axes.empty()) return out;

  // The kept walks with their drifts, jointly.
  ErrorModel joint = model;
  std::vector<Parameter> kept;
  for (int d : kept_axes) {
    joint.effects.push_back(trial.effects[static_cast<size_t>(WalkEffectOf(trial, d))]);
    kept.push_back({Kind::kSigma, d});
    kept.push_back({Kind::kWalk, d});
  }
  Maximiser em(run, joint, kept, filter, options, out);
  auto theta = FitInto(em, out, nullptr);
  if (!theta.ok()) return theta.status();
  const double l_hat = out.log_likelihood_after;

  for (size_t j = 0; j < kept.size(); ++j) {
    if (kept[j].kind != Kind::kWalk) continue;
    const int d = kept[j].drift;
    const auto i = static_cast<Eigen::Index>(j);
    WalkEstimate w;
    w.drift = d;
    w.effect = WalkName(d);
    // Its error with the drift σ's: over a bench run the two trade along a
    // ridge of the likelihood, and K's curvature alone would hide it.
    auto information = em.PairInformation(*theta, i - 1, i, l_hat);
    if (!information.ok()) return information.status();
    const bool definite = (*information)(0, 0) > 0.0 && information->determinant() > 0.0;
    const Eigen::Matrix2d covariance = definite ? Eigen::Matrix2d(information->inverse())
                                                : Eigen::Matrix2d::Constant(std::numeric_limits<double>::infinity());
    w.drift_sigma = EstimateOf(kept[j - 1], std::exp((*theta)[i - 1]), std::sqrt(covariance(0, 0)), a_priori);
    w.density = EstimateOf(kept[j], std::exp((*theta)[i]), std::sqrt(covariance(1, 1)), a_priori);
    // ℓ̂₀: the joint model without this walk, its drift σ re-fitted alone.
    // EM for σ alone starts from the model's σ, not the joint fit's: from a
    // σ the walk has relieved, EM crawls up and would stop below ℓ̂₀ (its
    // steps fall under the tolerance long before it gets there), which
    // inflates the statistic.
    ErrorModel without = out.model;
    without.effects.erase(without.effects.begin() + WalkEffectOf(without, d));
    DriftOf(without, d).sigma = DriftOf(model, d).sigma;
    DriftLikelihoodResult alone_result;
    Maximiser alone(run, without, {Parameter{Kind::kSigma, d}}, filter, options, alone_result);
    if (auto fitted = FitInto(alone, alone_result, nullptr); !fitted.ok()) return fitted.status();
    out.filter_passes += alone_result.filter_passes;
    w.log_likelihood_without = alone_result.log_likelihood_after;
    w.statistic = std::max(0.0, 2.0 * (l_hat - w.log_likelihood_without));
    out.identified.push_back(w.density);
    out.walks.push_back(std::move(w));
  }
  return out;
}

}  // namespace insdiag::engine::ident
