#include "insdiag/engine/ident/drift_likelihood.h"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "insdiag/engine/filter/smoother.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/model/parameter_field.h"
#include "insdiag/engine/model/state_layout.h"
#include "insdiag/engine/numerics/parallel_map.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine::ident {
namespace {

int EffectOf(const ErrorModel& m, const std::string& name) {
  auto terms = ParseEffectSelector(name);
  return terms.ok() ? m.FindEffect(terms->front()) : -1;
}
int WalkEffectOf(const ErrorModel& m, DriftAxis drift) { return EffectOf(m, WalkName(drift)); }
int PairEffectOf(const ErrorModel& m, DriftAxis drift) { return EffectOf(m, SecondOrderName(drift)); }

// One parameter of the likelihood: a drift's σ or τ, a walk's density K, or
// a second-order pair's σ₂, α or β.
enum class Kind { kSigma, kTau, kWalk, kPairSigma, kPairDecayRate, kPairFrequency };
struct Parameter {
  Kind kind = Kind::kSigma;
  DriftAxis drift;
};
bool IsPair(Kind k) { return k == Kind::kPairSigma || k == Kind::kPairDecayRate || k == Kind::kPairFrequency; }

// The parameter's value in a model: a reference into it (const for a const model).
template <typename Model>
auto& ValueOf(Model& m, const Parameter& p) {
  switch (p.kind) {
    case Kind::kSigma:
      return DriftOf(m, p.drift).sigma;
    case Kind::kTau:
      return DriftOf(m, p.drift).tau_s;
    case Kind::kWalk:
      return m.effects[static_cast<size_t>(WalkEffectOf(m, p.drift))].random_walk_density;
    case Kind::kPairSigma:
      return m.effects[static_cast<size_t>(PairEffectOf(m, p.drift))].second_order_sigma;
    case Kind::kPairDecayRate:
      return m.effects[static_cast<size_t>(PairEffectOf(m, p.drift))].second_order_alpha_per_s;
    case Kind::kPairFrequency:
      break;
  }
  return m.effects[static_cast<size_t>(PairEffectOf(m, p.drift))].second_order_beta_rad_s;
}

std::string NameOf(const Parameter& p) {
  switch (p.kind) {
    case Kind::kSigma:
      return DriftSigmaName(p.drift);
    case Kind::kTau:
      return DriftTauName(p.drift);
    case Kind::kWalk:
      return ParameterName(WalkName(p.drift), ParameterField::kDensity);
    case Kind::kPairSigma:
      return ParameterName(SecondOrderName(p.drift), ParameterField::kSigma);
    case Kind::kPairDecayRate:
      return ParameterName(SecondOrderName(p.drift), ParameterField::kDecayRate);
    case Kind::kPairFrequency:
      break;
  }
  return ParameterName(SecondOrderName(p.drift), ParameterField::kFrequency);
}

std::string_view UnitOf(const Parameter& p) {
  switch (p.kind) {
    case Kind::kSigma:
    case Kind::kPairSigma:
      return UnitsOf(p.drift.sensor).rate;
    case Kind::kTau:
      return "s";
    case Kind::kWalk:
      return UnitsOf(p.drift.sensor).rate_walk;
    case Kind::kPairDecayRate:
      return "1/s";
    case Kind::kPairFrequency:
      break;
  }
  return "rad/s";
}

// The M-step of a second-order pair (header: Second-order pairs) from its
// smoothed means (columns i, i+1 of x) and moments; false when the
// regression leaves the stationary region (ρ ≥ 1) or has no variance.
struct PairStep {
  double sigma = 0.0, alpha_per_s = 0.0, beta_rad_s = 0.0;
};
bool PairMStep(const Eigen::MatrixXd& x, int i, const Eigen::Matrix<double, Eigen::Dynamic, 7>& moments, double dt,
               PairStep& out) {
  const auto K = x.rows();
  Eigen::Matrix2d S00 = Eigen::Matrix2d::Zero(), S11 = Eigen::Matrix2d::Zero(), S10 = Eigen::Matrix2d::Zero();
  auto second_moment = [&](Eigen::Index k) {
    const Eigen::Vector2d m = x.block<1, 2>(k, i).transpose();
    Eigen::Matrix2d P;
    P << moments(k, 0), moments(k, 1), moments(k, 1), moments(k, 2);
    return Eigen::Matrix2d(m * m.transpose() + P);
  };
  for (Eigen::Index k = 0; k + 1 < K; ++k) {
    const Eigen::Vector2d m0 = x.block<1, 2>(k, i).transpose();
    const Eigen::Vector2d m1 = x.block<1, 2>(k + 1, i).transpose();
    Eigen::Matrix2d L;
    L << moments(k, 3), moments(k, 4), moments(k, 5), moments(k, 6);
    S00 += second_moment(k);
    S11 += second_moment(k + 1);
    S10 += m1 * m0.transpose() + L;
  }
  const double tr00 = S00.trace(), tr10 = S10.trace(), skew = S10(1, 0) - S10(0, 1);
  if (!(tr00 > 0.0)) return false;
  const double a = tr10 / tr00, b = skew / tr00;
  const double rho2 = a * a + b * b;
  const double q = (S11.trace() - 2.0 * (a * tr10 + b * skew) + rho2 * tr00) / (2.0 * static_cast<double>(K - 1));
  if (!(rho2 > 0.0 && rho2 < 1.0 && q > 0.0)) return false;
  out.sigma = std::sqrt(q / (1.0 - rho2));
  out.alpha_per_s = -0.5 * std::log(rho2) / dt;
  out.beta_rad_s = std::abs(std::atan2(b, a)) / dt;
  return out.beta_rad_s > 0.0;
}

// Whether a cycle's likelihood gain `gain`, after `last_gain` (NaN: none
// yet), leaves less than `tolerance` to gain (DriftLikelihoodOptions::
// likelihood_tolerance): EM's gains shrink geometrically near the maximum,
// by r = gain / last_gain a cycle, so what remains is gain · r / (1 − r).
// A gain that does not shrink (r ≥ 1) is EM crawling, not converging.
bool LikelihoodSettled(double gain, double last_gain, double tolerance) {
  if (!(gain < tolerance)) return false;
  if (gain <= 0.0) return true;
  if (!(last_gain > 0.0)) return false;
  const double r = gain / last_gain;
  return r < 1.0 && gain * r / (1.0 - r) < tolerance;
}

// EM over θ = ln of each parameter (header), with the pass count of `out`.
class Maximiser {
 public:
  Maximiser(const EpochRun& run, ErrorModel model, std::vector<Parameter> parameters,
            const DriftLikelihoodOptions& options, DriftLikelihoodResult& out)
      : run_(run), model_(std::move(model)), layout_(model_), parameters_(std::move(parameters)), 
        options_(options), out_(out) {
    for (const Parameter& p : parameters_) {
      if (p.kind == Kind::kTau) tau_free_.Set(p.drift);
      if (p.kind == Kind::kPairSigma) {
        pair_slot_[static_cast<size_t>(p.drift.Index())] = static_cast<int>(smoother_.pair_states.size());
        smoother_.pair_states.push_back(layout_.EffectOffset(PairEffectOf(model_, p.drift)));
      }
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
    auto fw = RunForwardFilter(run_, m);
    if (!fw.ok()) return fw.status();
    return fw->log_likelihood;
  }

  // ℓ at each of `probes`: independent passes, on every core.
  absl::StatusOr<std::vector<double>> LogLikelihoods(const std::vector<Eigen::VectorXd>& probes) {
    out_.filter_passes += static_cast<int>(probes.size());
    const auto values = numerics::ParallelMap(probes.size(), [&](std::size_t i) -> absl::StatusOr<double> {
      auto fw = RunForwardFilter(run_, ModelOf(probes[i]));
      if (!fw.ok()) return fw.status();
      return fw->log_likelihood;
    });
    std::vector<double> out;
    out.reserve(values.size());
    for (const absl::StatusOr<double>& v : values) {
      if (!v.ok()) return v.status();
      out.push_back(*v);
    }
    return out;
  }

  // ℓ(θ) and the M-step's θ.
  struct Step {
    double log_likelihood;
    Eigen::VectorXd next;
  };
  absl::StatusOr<Step> EmStep(const Eigen::VectorXd& theta) {
    ++out_.filter_passes;
    auto fw = RunForwardFilter(run_, ModelOf(theta));
    if (!fw.ok()) return fw.status();
    const int K = fw->epochs();
    if (K < 3) return absl::InvalidArgumentError("drift likelihood: the run has fewer than three epochs");
    auto sm = RunSmoother(*fw, smoother_);
    if (!sm.ok()) return sm.status();
    const double dt = (fw->epoch_time_s.back() - fw->epoch_time_s.front()) / (K - 1);
    Step step{fw->log_likelihood, theta};
    for (size_t j = 0; j < parameters_.size(); ++j) {
      const Parameter& p = parameters_[j];
      const auto i = static_cast<Eigen::Index>(j);
      if (IsPair(p.kind)) {
        const int slot = pair_slot_[static_cast<size_t>(p.drift.Index())];
        PairStep pair;
        if (!PairMStep(sm->x, smoother_.pair_states[static_cast<size_t>(slot)], sm->pair_moments[static_cast<size_t>(slot)],
                       dt, pair)) {
          continue;
        }
        step.next[i] = std::log(p.kind == Kind::kPairSigma       ? pair.sigma
                                : p.kind == Kind::kPairDecayRate ? pair.alpha_per_s
                                                                 : pair.beta_rad_s);
        continue;
      }
      const bool walk = p.kind == Kind::kWalk;
      const int bias = p.drift.sensor == Sensor::kGyro ? layout_.gyro_bias() : layout_.acc_bias();
      const int state = walk ? layout_.EffectOffset(WalkEffectOf(model_, p.drift)) : bias + p.drift.axis;
      double a_from = 0.0, a_to = 0.0, b = 0.0;
      for (int k = 0; k + 1 < K; ++k) {
        const double x0 = sm->x(k, state), x1 = sm->x(k + 1, state);
        a_from += x0 * x0 + sm->variance(k, state);
        a_to += x1 * x1 + sm->variance(k + 1, state);
        b += x1 * x0 + sm->lag_one_covariance(k, state);
      }
      const double a0 = sm->x(0, state) * sm->x(0, state) + sm->variance(0, state);
      if (walk) {
        const double k2 = (a_to - 2.0 * b + a_from) / ((K - 1) * dt);  // K̂²
        if (k2 > 0.0) step.next[i] = 0.5 * std::log(k2);
      } else if (tau_free_.Contains(p.drift)) {
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
    double cycle_start_likelihood = 0.0;
    double last_gain = std::numeric_limits<double>::quiet_NaN();
    for (int cycle = 0, iterations = 0; iterations < options_.max_iterations; ++cycle) {
      auto first = EmStep(theta);
      if (!first.ok()) return first.status();
      if (cycle == 0 && first_likelihood != nullptr) *first_likelihood = first->log_likelihood;
      if (cycle > 0) {
        const double gain = first->log_likelihood - cycle_start_likelihood;
        if (LikelihoodSettled(gain, last_gain, options_.likelihood_tolerance)) {
          converged_ = true;
          iterations_ = iterations + 1;
          return first->next;
        }
        last_gain = gain;
      }
      cycle_start_likelihood = first->log_likelihood;
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
        // An extrapolation far out along a ridge can leave a model whose
        // smoother fails (two states the run cannot tell apart, their
        // covariance singular): that step is refused, as one whose
        // likelihood falls is.
        auto third = EmStep(extrapolated);
        ++iterations;
        if (third.ok() && third->log_likelihood >= second->log_likelihood) next = third->next;
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
    std::vector<Eigen::VectorXd> probes(2, theta);
    probes[0][j] += h;
    probes[1][j] -= h;
    auto shifted = LogLikelihoods(probes);
    if (!shifted.ok()) return shifted.status();
    return -((*shifted)[0] - 2.0 * l0 + (*shifted)[1]) / (h * h);
  }

  // Observed information of the block of parameters `at` at θ (ℓ(θ) = l0):
  // second differences, the mixed ones from the diagonal shifts
  // (Abramowitz & Stegun 25.3.27); r(r + 1) passes for r parameters.
  absl::StatusOr<Eigen::MatrixXd> BlockInformation(const Eigen::VectorXd& theta, const std::vector<Eigen::Index>& at,
                                                   double l0) {
    const double h = options_.curvature_step;
    const auto r = static_cast<Eigen::Index>(at.size());
    // The probes: each parameter up and down, then each pair up together and
    // down together.
    std::vector<Eigen::VectorXd> probes;
    auto probe = [&](Eigen::Index a, double da, Eigen::Index b, double db) {
      Eigen::VectorXd p = theta;
      p[at[static_cast<size_t>(a)]] += da;
      p[at[static_cast<size_t>(b)]] += db;
      probes.push_back(std::move(p));
    };
    for (Eigen::Index a = 0; a < r; ++a) {
      probe(a, h, a, 0.0);
      probe(a, -h, a, 0.0);
    }
    for (Eigen::Index a = 0; a < r; ++a) {
      for (Eigen::Index b = a + 1; b < r; ++b) {
        probe(a, h, b, h);
        probe(a, -h, b, -h);
      }
    }
    auto values = LogLikelihoods(probes);
    if (!values.ok()) return values.status();
    const std::vector<double>& l = *values;
    const auto up = [&](Eigen::Index a) { return l[static_cast<size_t>(2 * a)]; };
    const auto down = [&](Eigen::Index a) { return l[static_cast<size_t>(2 * a + 1)]; };
    Eigen::MatrixXd information(r, r);
    size_t pair = static_cast<size_t>(2 * r);
    for (Eigen::Index a = 0; a < r; ++a) {
      information(a, a) = -(up(a) - 2.0 * l0 + down(a)) / (h * h);
      for (Eigen::Index b = a + 1; b < r; ++b, pair += 2) {
        information(a, b) = information(b, a) =
            -(l[pair] + l[pair + 1] - up(a) - down(a) - up(b) - down(b) + 2.0 * l0) / (2.0 * h * h);
      }
    }
    return information;
  }

  const std::vector<Parameter>& parameters() const { return parameters_; }
  bool converged() const { return converged_; }
  int iterations() const { return iterations_; }

 private:
  const EpochRun& run_;
  ErrorModel model_;
  StateLayout layout_;
  std::vector<Parameter> parameters_;
  const DriftLikelihoodOptions& options_;
  DriftLikelihoodResult& out_;
  DriftSelection tau_free_;  // drifts whose τ is a parameter too
  SmootherOptions smoother_;   // with the moments of each fitted pair
  std::array<int, DriftAxis::kCount> pair_slot_{};  // by DriftAxis::Index: its pair's index among smoother_.pair_states
  bool converged_ = false;
  int iterations_ = 0;
};

absl::Status ValidateOptions(const DriftLikelihoodOptions& options) {
  if (!(options.max_iterations > 0 && options.second_order_max_iterations > 0 && options.log_tolerance > 0.0 &&
        options.likelihood_tolerance > 0.0 &&
        options.curvature_step > 0.0)) {
    return absl::InvalidArgumentError("drift likelihood options out of range");
  }
  return absl::OkStatus();
}

bool HasDrift(const ErrorModel& m, DriftAxis drift) { return DriftOf(m, drift).sigma > 0.0 && DriftOf(m, drift).tau_s > 0.0; }

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
  e.method = EstimationMethod::kMaximumLikelihood;
  e.unit = std::string(UnitOf(p));
  if (p.kind == Kind::kSigma || p.kind == Kind::kTau) e.a_priori = ValueOf(a_priori, p);
  return e;
}

}  // namespace

double StructurePValue(double statistic, int dof, int starts) {
  return std::min(1.0, stats::ChiSquareSurvival(statistic, dof) * static_cast<double>(starts));
}

double NestedPValue(const StructureEstimate& s) { return StructurePValue(s.statistic, s.dof, s.starts); }

absl::StatusOr<DriftLikelihoodResult> IdentifyDriftsByLikelihood(const EpochRun& run, const ErrorModel& model,
                                                                 const ErrorModel& a_priori,
                                                                 const DriftSelection& which,
                                                                 const DriftSelection& tau_too,
                                                                 const DriftLikelihoodOptions& options) {
  if (auto st = ValidateOptions(options); !st.ok()) return st;
  DriftLikelihoodResult out;
  out.model = model;
  std::vector<Parameter> parameters;
  for (const DriftAxis d : DriftAxis::All()) {
    // A drift the model leaves out (σ = 0) has no state to identify.
    if (!which.Contains(d) || !HasDrift(model, d)) continue;
    parameters.push_back({Kind::kSigma, d});
    if (tau_too.Contains(d)) parameters.push_back({Kind::kTau, d});
  }
  if (parameters.empty()) {
    out.converged = true;
    return out;
  }
  Maximiser em(run, model, parameters, options, out);
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
      auto information = em.BlockInformation(*theta, {i, i + 1}, l0);
      if (!information.ok()) return information.status();
      if ((*information)(0, 0) > 0.0 && information->determinant() > 0.0) {
        const Eigen::MatrixXd covariance = information->inverse();
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

namespace {

// A structure kind the likelihood tests: its parameters after the axis'
// drift σ (the first is its magnitude) and its effect at a start.
struct StructureKind {
  bool second_order = false;
  std::string Name(DriftAxis drift) const { return second_order ? SecondOrderName(drift) : WalkName(drift); }
  std::vector<Kind> Kinds() const {
    if (second_order) return {Kind::kPairSigma, Kind::kPairDecayRate, Kind::kPairFrequency};
    return {Kind::kWalk};
  }
  // Starting points: one for a walk, one per starting period for a pair.
  size_t Starts(const DriftLikelihoodOptions& o) const {
    return second_order ? o.second_order_start_periods_s.size() : 1;
  }
  // The effect at start `start` for a drift of a-priori σ and τ `specified`
  // (header: a walk at the drift's short-term level σ√(2/τ); a pair of the
  // drift's σ, its decay time the starting period).
  absl::StatusOr<ModelEffect> At(DriftAxis drift, size_t start, const GaussMarkov& specified,
                                 const DriftLikelihoodOptions& o) const {
    auto terms = ParseEffectSelector(Name(drift));
    if (!terms.ok()) return terms.status();
    ModelEffect e;
    e.term = terms->front();
    if (second_order) {
      const double period_s = o.second_order_start_periods_s[start];
      e.second_order_sigma = specified.sigma;
      e.second_order_alpha_per_s = 1.0 / period_s;
      e.second_order_beta_rad_s = 2.0 * std::numbers::pi / period_s;
    } else {
      e.random_walk_density = specified.sigma * std::sqrt(2.0 / specified.tau_s);
    }
    return e;
  }
};

// The report's parameters of a fitted structure from its estimates in θ
// (value, SE of its log): a walk's K; a pair's σ₂, τ₂ = 1/α and period 2π/β
// (ln τ₂ = −ln α: the same SE in the log).
std::vector<ParameterEstimate> ReportedParameters(const StructureKind& kind, DriftAxis drift,
                                                  const std::vector<ParameterEstimate>& fitted) {
  if (!kind.second_order) return fitted;
  std::vector<ParameterEstimate> out{fitted[0]};
  for (size_t k = 1; k < 3; ++k) {
    ParameterEstimate e = fitted[k];
    const double log_se = e.std_error / e.value;
    const double scale = k == 1 ? 1.0 : 2.0 * std::numbers::pi;
    e.name = ParameterName(SecondOrderName(drift),
                           k == 1 ? ParameterField::kTau : ParameterField::kPeriod);
    e.value = scale / fitted[k].value;
    e.std_error = e.value * log_se;
    e.ci95_low = e.value * std::exp(-1.96 * log_se);
    e.ci95_high = e.value * std::exp(1.96 * log_se);
    e.unit = std::string("s");
    out.push_back(e);
  }
  return out;
}

// The drift a structure's start is scaled to: the a-priori model's where it
// has one, else the model's.
const GaussMarkov& SpecifiedDrift(const ErrorModel& model, const ErrorModel& a_priori,
                                  DriftAxis d) {
  return HasDrift(a_priori, d) ? DriftOf(a_priori, d) : DriftOf(model, d);
}

// The axes whose structure the screen keeps, each with its best start.
struct ScreenedStructures {
  std::vector<DriftAxis> kept_axes;
  std::array<size_t, DriftAxis::kCount> best_start{};  // by DriftAxis::Index
};

// The screen: from each start, every candidate at the structure hypothesis
// (the drift at its a-priori σ, not wider: a widened drift took the slow
// variance the structure would explain), one EM step; an axis keeps the
// start whose step lets the magnitude grow most. The starts' steps are
// independent passes: on every core, read in order.
absl::StatusOr<ScreenedStructures> ScreenStructureStarts(
    const EpochRun& run, const ErrorModel& model, const ErrorModel& a_priori,
    const std::vector<DriftAxis>& candidates, const StructureKind& kind,
    const DriftLikelihoodOptions& options, DriftLikelihoodResult& out) {
  const std::vector<Kind> kinds = kind.Kinds();
  const auto per_axis = static_cast<Eigen::Index>(kinds.size()) + 1;
  struct ScreenStep {
    Eigen::VectorXd theta;
    Maximiser::Step step;
    int filter_passes = 0;
  };
  auto screened = numerics::ParallelMap(kind.Starts(options), [&](std::size_t start) -> absl::StatusOr<ScreenStep> {
    ErrorModel trial = model;
    std::vector<Parameter> parameters;
    for (const DriftAxis d : candidates) {
      auto effect = kind.At(d, start, SpecifiedDrift(model, a_priori, d), options);
      if (!effect.ok()) return effect.status();
      GaussMarkov& drift = DriftOf(trial, d);
      drift.sigma = std::min(drift.sigma, SpecifiedDrift(model, a_priori, d).sigma);
      trial.effects.push_back(*effect);
      parameters.push_back({Kind::kSigma, d});
      for (Kind k : kinds) parameters.push_back({k, d});
    }
    DriftLikelihoodResult passes;
    Maximiser screen(run, trial, parameters, options, passes);
    ScreenStep out_step{screen.Start(), {}, 0};
    auto step = screen.EmStep(out_step.theta);
    if (!step.ok()) return step.status();
    out_step.step = *std::move(step);
    out_step.filter_passes = passes.filter_passes;
    return out_step;
  });
  ScreenedStructures result;
  std::array<double, DriftAxis::kCount> best_growth;
  best_growth.fill(0.0);
  for (size_t start = 0; start < screened.size(); ++start) {
    if (!screened[start].ok()) return screened[start].status();
    const ScreenStep& s_step = *screened[start];
    out.filter_passes += s_step.filter_passes;
    if (start == 0) out.log_likelihood_before = s_step.step.log_likelihood;
    for (size_t c = 0; c < candidates.size(); ++c) {
      const auto magnitude = static_cast<Eigen::Index>(c) * per_axis + 1;
      const double growth = s_step.step.next[magnitude] - s_step.theta[magnitude];
      const auto d = static_cast<size_t>(candidates[c].Index());
      if (growth > best_growth[d]) {
        best_growth[d] = growth;
        result.best_start[d] = start;
      }
    }
  }
  for (const DriftAxis d : candidates) {
    if (best_growth[static_cast<size_t>(d.Index())] > 0.0) result.kept_axes.push_back(d);
  }
  return result;
}

// Each kept structure's nested test: ℓ̂₀ is the joint model's without it, its
// drift σ re-fitted alone. EM for σ alone starts from the model's σ, not the
// joint fit's: from a σ the structure has relieved, EM crawls up and would
// stop below ℓ̂₀ (its steps fall under the tolerance long before it gets
// there), which inflates the statistic. The fits are independent: on every
// core.
absl::StatusOr<std::vector<StructureEstimate>> TestEachWithoutIt(
    const EpochRun& run, const ErrorModel& model, const std::vector<DriftAxis>& kept_axes,
    const StructureKind& kind, const DriftLikelihoodOptions& options, DriftLikelihoodResult& out) {
  auto without_each = numerics::ParallelMap(kept_axes.size(), [&](std::size_t c) {
    const DriftAxis d = kept_axes[c];
    ErrorModel without = out.model;
    without.effects.erase(without.effects.begin() + EffectOf(without, kind.Name(d)));
    DriftOf(without, d).sigma = DriftOf(model, d).sigma;
    DriftLikelihoodResult alone_result;
    Maximiser alone(run, without, {Parameter{Kind::kSigma, d}}, options, alone_result);
    absl::Status fitted = FitInto(alone, alone_result, nullptr).status();
    return std::pair{fitted, alone_result};
  });
  std::vector<StructureEstimate> fits;
  for (size_t c = 0; c < kept_axes.size(); ++c) {
    const auto& [fitted_alone, alone_result] = without_each[c];
    if (!fitted_alone.ok()) return fitted_alone;
    const DriftAxis d = kept_axes[c];
    StructureEstimate w;
    w.drift = d;
    w.effect = kind.Name(d);
    w.dof = static_cast<int>(kind.Kinds().size());
    w.starts = static_cast<int>(kind.Starts(options));
    out.filter_passes += alone_result.filter_passes;
    w.log_likelihood_without = alone_result.log_likelihood_after;
    w.statistic = std::max(0.0, 2.0 * (out.log_likelihood_after - w.log_likelihood_without));
    fits.push_back(std::move(w));
  }
  return fits;
}

// Fits a structure of `kind` on each selected axis with its drift σ (header:
// Walks, Second-order pairs): the screen's first EM step from each start,
// the kept axes jointly from their best starts, each tested against the
// model without it.
absl::StatusOr<DriftLikelihoodResult> FitStructures(const EpochRun& run, const ErrorModel& model,
                                                    const ErrorModel& a_priori,
                                                    const DriftSelection& axes,
                                                    const StructureKind& kind, double screen_alpha,
                                                    const DriftLikelihoodOptions& options) {
  if (auto st = ValidateOptions(options); !st.ok()) return st;
  DriftLikelihoodResult out;
  out.model = model;
  out.converged = true;
  const std::vector<Kind> kinds = kind.Kinds();
  const auto per_axis =
      static_cast<Eigen::Index>(kinds.size()) + 1;  // the drift σ, then the structure's

  std::vector<DriftAxis> candidates;
  for (const DriftAxis d : DriftAxis::All()) {
    if (axes.Contains(d) && HasDrift(model, d) && EffectOf(model, kind.Name(d)) < 0) {
      candidates.push_back(d);
      out.screened.Set(d);
    }
  }
  if (candidates.empty()) return out;
  auto screen = ScreenStructureStarts(run, model, a_priori, candidates, kind, options, out);
  if (!screen.ok()) return screen.status();
  const std::vector<DriftAxis>& kept_axes = screen->kept_axes;
  if (kept_axes.empty()) return out;

  // The kept structures with their drifts, jointly, each from its best start.
  ErrorModel joint = model;
  std::vector<Parameter> kept;
  for (const DriftAxis d : kept_axes) {
    auto effect = kind.At(d, screen->best_start[static_cast<size_t>(d.Index())],
                          SpecifiedDrift(model, a_priori, d), options);
    if (!effect.ok()) return effect.status();
    joint.effects.push_back(*effect);
    kept.push_back({Kind::kSigma, d});
    for (Kind k : kinds) kept.push_back({k, d});
  }
  // A pair's joint fit is capped (options): past the cap its statistic is a
  // lower bound. A structure significant at the cap is fitted on to
  // convergence before its errors are taken: the information is that of
  // the maximum, not of a point on the way to it.
  DriftLikelihoodOptions capped = options;
  if (kind.second_order)
    capped.max_iterations = std::min(options.max_iterations, options.second_order_max_iterations);
  Maximiser em(run, joint, kept, capped, out);
  auto theta = FitInto(em, out, nullptr);
  if (!theta.ok()) return theta.status();

  auto tested = TestEachWithoutIt(run, model, kept_axes, kind, options, out);
  if (!tested.ok()) return tested.status();
  std::vector<StructureEstimate> fits = std::move(*tested);
  auto significant = [&](const StructureEstimate& w) { return NestedPValue(w) < screen_alpha; };
  if (!out.converged && std::any_of(fits.begin(), fits.end(), significant)) {
    const int capped_iterations = out.iterations;
    Maximiser on(run, out.model, kept, options, out);
    theta = FitInto(on, out, nullptr);
    if (!theta.ok()) return theta.status();
    out.iterations += capped_iterations;
    for (StructureEstimate& w : fits) {
      w.statistic = std::max(0.0, 2.0 * (out.log_likelihood_after - w.log_likelihood_without));
    }
  }
  const double l_hat = out.log_likelihood_after;
  Maximiser at_estimate(run, out.model, kept, options, out);
  for (size_t c = 0; c < fits.size(); ++c) {
    StructureEstimate& w = fits[c];
    const auto first = static_cast<Eigen::Index>(c) * per_axis;
    w.fitted = out.model.effects[static_cast<size_t>(EffectOf(out.model, w.effect))];
    // Its errors with the drift σ's (and a pair's with each other): over a
    // bench run they trade along ridges of the likelihood, and one
    // parameter's curvature alone would hide it. Only for a structure the
    // nested test keeps: the block costs r(r + 1) passes.
    Eigen::MatrixXd covariance = Eigen::MatrixXd::Constant(per_axis, per_axis, std::numeric_limits<double>::quiet_NaN());
    if (significant(w)) {
      std::vector<Eigen::Index> block;
      for (Eigen::Index k = 0; k < per_axis; ++k) block.push_back(first + k);
      auto information = at_estimate.BlockInformation(*theta, block, l_hat);
      if (!information.ok()) return information.status();
      covariance = StructureCovariance(*information);
    }
    auto estimate = [&](Eigen::Index k) {
      return EstimateOf(kept[static_cast<size_t>(first + k)], std::exp((*theta)[first + k]), std::sqrt(covariance(k, k)),
                        a_priori);
    };
    w.drift_sigma = estimate(0);
    std::vector<ParameterEstimate> fitted;
    for (Eigen::Index k = 1; k < per_axis; ++k) fitted.push_back(estimate(k));
    w.parameters = ReportedParameters(kind, w.drift, fitted);
    out.identified.insert(out.identified.end(), w.parameters.begin(), w.parameters.end());
    out.structures.push_back(std::move(w));
  }
  return out;
}

}  // namespace

Eigen::MatrixXd StructureCovariance(const Eigen::MatrixXd& information) {
  const Eigen::Index n = information.rows();
  Eigen::MatrixXd covariance = Eigen::MatrixXd::Constant(n, n, std::numeric_limits<double>::infinity());
  const Eigen::LLT<Eigen::MatrixXd> llt(information);
  if (llt.info() == Eigen::Success) return llt.solve(Eigen::MatrixXd::Identity(n, n));
  if (n > 1 && information(0, 0) <= 0.0) {
    const Eigen::Index r = n - 1;
    const Eigen::LLT<Eigen::MatrixXd> own(information.bottomRightCorner(r, r));
    if (own.info() == Eigen::Success) covariance.bottomRightCorner(r, r) = own.solve(Eigen::MatrixXd::Identity(r, r));
  }
  return covariance;
}

absl::StatusOr<DriftLikelihoodResult> IdentifyWalksByLikelihood(const EpochRun& run, const ErrorModel& model,
                                                                const ErrorModel& a_priori,
                                                                const DriftSelection& axes, double screen_alpha,
                                                                const DriftLikelihoodOptions& options) {
  return FitStructures(run, model, a_priori, axes, StructureKind{false}, screen_alpha, options);
}

absl::StatusOr<DriftLikelihoodResult> IdentifySecondOrdersByLikelihood(const EpochRun& run, const ErrorModel& model,
                                                                       const ErrorModel& a_priori,
                                                                       const DriftSelection& axes,
                                                                       double screen_alpha,
                                                                       const DriftLikelihoodOptions& options) {
  if (options.second_order_start_periods_s.empty() ||
      std::any_of(options.second_order_start_periods_s.begin(), options.second_order_start_periods_s.end(),
                  [](double p) { return !(p > 0.0); })) {
    return absl::InvalidArgumentError("drift likelihood: second-order starting periods must be positive");
  }
  return FitStructures(run, model, a_priori, axes, StructureKind{true}, screen_alpha, options);
}

}  // namespace insdiag::engine::ident
