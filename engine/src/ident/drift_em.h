// The drift likelihood's expectation–maximisation, shared by the
// identification of drifts and the structure tests on top of it (both in
// drift_likelihood.cc). Private to the engine; the equations are in
// drift_likelihood.h.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "insdiag/engine/filter/smoother.h"
#include "insdiag/engine/ident/drift_likelihood.h"
#include "insdiag/engine/model/state_layout.h"

namespace insdiag::engine::ident::drift_em {

// The model's index of the effect a selector names; −1 where it has none.
int EffectOf(const ErrorModel& m, const std::string& name);
inline int WalkEffectOf(const ErrorModel& m, DriftAxis drift) {
  return EffectOf(m, WalkName(drift));
}
inline int PairEffectOf(const ErrorModel& m, DriftAxis drift) {
  return EffectOf(m, SecondOrderName(drift));
}

// One parameter of the likelihood: a drift's σ or τ, a walk's density K, or
// a second-order pair's σ₂, α or β.
enum class Kind { kSigma, kTau, kWalk, kPairSigma, kPairDecayRate, kPairFrequency };
struct Parameter {
  Kind kind = Kind::kSigma;
  DriftAxis drift;
};
inline bool IsPair(Kind k) {
  return k == Kind::kPairSigma || k == Kind::kPairDecayRate || k == Kind::kPairFrequency;
}

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

std::string NameOf(const Parameter& p);
std::string_view UnitOf(const Parameter& p);

// EM over θ = ln of each parameter (header), with the pass count of `out`.
class Maximiser {
 public:
  Maximiser(const EpochRun& run, ErrorModel model, std::vector<Parameter> parameters,
            const DriftLikelihoodOptions& options, DriftLikelihoodResult& out);

  // θ at the model's values; the model at θ; ℓ of a model (one forward pass).
  Eigen::VectorXd Start() const;
  ErrorModel ModelOf(const Eigen::VectorXd& theta) const;
  absl::StatusOr<double> LogLikelihood(const ErrorModel& m);

  // ℓ at each of `probes`: independent passes, on every core.
  absl::StatusOr<std::vector<double>> LogLikelihoods(const std::vector<Eigen::VectorXd>& probes);

  // ℓ(θ) and the M-step's θ.
  struct Step {
    double log_likelihood;
    Eigen::VectorXd next;
  };
  absl::StatusOr<Step> EmStep(const Eigen::VectorXd& theta);

  // SQUAREM, scheme S3 (Varadhan & Roland 2008): two EM steps give
  // r = θ₁ − θ₀ and v = θ₂ − 2θ₁ + θ₀; with α = −‖r‖/‖v‖ (at most −1, which
  // is θ₂ itself) θ′ = θ₀ − 2αr + α²v, whose EM step continues the cycle when
  // its likelihood is not below θ₂'s. A step length per parameter: they are
  // near-independent, and one that crawls must not wait for the others.
  // Returns the maximiser; `first_likelihood` gets ℓ at the start.
  absl::StatusOr<Eigen::VectorXd> Maximise(Eigen::VectorXd theta, double* first_likelihood);

  // Observed information in θ_j at θ (ℓ(θ) = l0): the second difference.
  absl::StatusOr<double> Information(const Eigen::VectorXd& theta, Eigen::Index j, double l0);

  // Observed information of the block of parameters `at` at θ (ℓ(θ) = l0):
  // second differences, the mixed ones from the diagonal shifts
  // (Abramowitz & Stegun 25.3.27); r(r + 1) passes for r parameters.
  absl::StatusOr<Eigen::MatrixXd> BlockInformation(const Eigen::VectorXd& theta,
                                                   const std::vector<Eigen::Index>& at, double l0);

  // Observed information of the block of parameters `at` at θ from the
  // smoother's moments, by Oakes' identity (JRSS B 61(2), 1999, 479;
  // Louis, JRSS B 44(2), 1982, 226, with the missing information written as a
  // derivative):
  //   I(θ) = −[∂²Q(θ′|θ)/∂θ′∂θ′ᵀ + ∂²Q(θ′|θ)/∂θ′∂θᵀ]  at θ′ = θ,
  // Q the expected complete-data log-likelihood under the smoother at θ.
  // The first term (the complete information) is analytic in the smoothed
  // sums of each drift, walk or pair state (drift_em.cc); the second, the
  // missing information, is the change of the complete-data score at θ′ = θ
  // as the smoother's θ moves: one filter and smoother pass at θ and two at
  // θ ± h e_j per parameter j of `at` (h = DriftLikelihoodOptions::
  // moment_information_step), 2r + 1 passes in all, on every core. Central,
  // not forward: where the run observes a state little the missing
  // information is nearly all of the complete (a walk beside its drift:
  // 11,911 of 12,155, leaving 244), and a forward difference's O(h) error
  // in it (5 % of a gyro drift's SE, the walk's block indefinite at
  // h = 10⁻³) is the observed information's; central, h = 10⁻³ and 10⁻⁴
  // give the same SEs to 0.2 %. Louis's
  // own form of the missing information, Var[complete score | y], is a
  // double sum over every pair of epochs of the smoothed cross-covariances
  // E[x_k x_{k+1} x_l x_{l+1} | y] − …: O(N²) products of the RTS gains,
  // which the smoother does not keep; the derivative costs 2r passes.
  // Symmetrised (the identity makes it symmetric; the difference does so to
  // its truncation).
  absl::StatusOr<Eigen::MatrixXd> MomentInformation(const Eigen::VectorXd& theta,
                                                    const std::vector<Eigen::Index>& at);

  const std::vector<Parameter>& parameters() const { return parameters_; }
  bool converged() const { return converged_; }
  int iterations() const { return iterations_; }

 private:
  // The smoother's pass at θ: ℓ, the smoothed moments, the epoch count and
  // the mean update interval (the M-step's and the information's inputs).
  struct Smoothed {
    double log_likelihood = 0.0;
    SmoothedPass pass;
    int epochs = 0;
    double dt = 0.0;
  };
  absl::StatusOr<Smoothed> SmoothedAt(const Eigen::VectorXd& theta) const;
  // The score of Q(θ′|θ) in θ′ from a smoothed pass at θ (its sums), and
  // where `hessian` is given its Hessian in θ′, over every parameter.
  struct CompleteDerivatives {
    Eigen::VectorXd score;
    Eigen::MatrixXd hessian;  // empty unless asked for
  };
  absl::StatusOr<CompleteDerivatives> CompleteDataDerivatives(const Eigen::VectorXd& smoothed_at,
                                                              const Eigen::VectorXd& theta_prime,
                                                              bool hessian) const;
  // The index of a parameter in θ; −1 where it is not one.
  Eigen::Index IndexOf(Kind kind, DriftAxis drift) const;

  const EpochRun& run_;
  ErrorModel model_;
  StateLayout layout_;
  std::vector<Parameter> parameters_;
  const DriftLikelihoodOptions& options_;
  DriftLikelihoodResult& out_;
  DriftSelection tau_free_;   // drifts whose τ is a parameter too
  SmootherOptions smoother_;  // with the moments of each fitted pair
  std::array<int, DriftAxis::kCount>
      pair_slot_{};  // by DriftAxis::Index: its pair's index among smoother_.pair_states
  bool converged_ = false;
  int iterations_ = 0;
};

absl::Status ValidateOptions(const DriftLikelihoodOptions& options);

// Whether the model carries the drift as a state (σ and τ both positive).
bool HasDrift(const ErrorModel& m, DriftAxis drift);

// Maximises from the model's values into `out` (model, iterations,
// convergence, ℓ at the estimate); `first_likelihood` gets ℓ at the start.
absl::StatusOr<Eigen::VectorXd> FitInto(Maximiser& em, DriftLikelihoodResult& out,
                                        double* first_likelihood);

// The report's estimate of a parameter at `value`, with its SE from the log's.
ParameterEstimate EstimateOf(const Parameter& p, double value, double log_se,
                             const ErrorModel& a_priori);

// An EM fit of drifts whose errors are not taken yet: where several fits
// compete (starts, a combination), they are compared on their maxima and
// only the chosen one's information is computed (r(r + 1) passes a drift).
struct FitWithoutErrors {
  DriftLikelihoodResult result;  // `identified` and `not_identifiable` empty
  ErrorModel start;               // the model given: a flat direction keeps its value
  std::vector<Parameter> parameters;
  Eigen::VectorXd theta;  // where EM stopped, in the parameters' order
};

// IdentifyDriftsByLikelihood (drift_likelihood.h) without the errors.
absl::StatusOr<FitWithoutErrors> FitDriftsWithinCeilings(const EpochRun& run, const ErrorModel& model,
                                                         const ErrorModel& a_priori, const DriftSelection& which,
                                                         const DriftSelection& tau_too,
                                                         const DriftCeilings& ceilings,
                                                         const DriftLikelihoodOptions& options);

// The fit with its errors: the observed information at θ in ln σ, or in
// (ln σ, ln τ) jointly where τ is identified too. A drift whose likelihood
// is flat there keeps the start's values and is listed not identifiable.
absl::StatusOr<DriftLikelihoodResult> WithErrors(const EpochRun& run, FitWithoutErrors fit,
                                                 const ErrorModel& a_priori,
                                                 const DriftLikelihoodOptions& options);

}  // namespace insdiag::engine::ident::drift_em
