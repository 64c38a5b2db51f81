// Maximum-likelihood identification of the base drifts' σ and τ, and of the
// bias random walks (catalogue: gyro_bias_rw, acc_bias_rw) the drifts may hide.
//
// Why. Correlation processing (correlation.h) fits the ACF of the smoothed
// drift estimates. The smoother shrinks those estimates towards what the
// model expects: when the model's σ is far too small (a worn gyro whose drift
// σ has tripled) the smoothed drift is flattened, its ACF looks like a walk,
// and the fit cannot bound τ — the drift is "unresolved" however strongly the
// innovations say the model is wrong. Where it is resolved, the shrinkage
// still biases σ and τ low together along the fit's ridge (horizontal gyro
// drifts: 78 % coverage of the fit's 95 % intervals). The innovation
// likelihood does not depend on the smoother's shrinkage: it is the
// likelihood of the data under the model, and its maximum is the estimate.
//
// What. σ of each selected drift, and τ of those the caller names: where
// correlation processing resolved the drift (its estimate, in the model, is
// a start near the maximum) or where the model's τ is a placeholder. A bench
// run spans a few correlation times, and over so few the likelihood in
// (σ, τ) is a long curved ridge with more than one local maximum (a long τ
// with a small σ looks like a short τ with a large one over a few hours);
// σ at a given τ is well determined and its likelihood is unimodal, so τ of
// a drift the run does not resolve is held at the model's value.
//
// How. Expectation–maximisation over the state-space model (Shumway &
// Stoffer, J. Time Series Anal. 3(4), 1982; Shumway & Stoffer, Time Series
// Analysis and Its Applications, 4th ed., §6.3): each drift is a first-order
// Gauss–Markov state sampled at the epochs (seed eq. 5),
//   x₀ ~ N(0, σ²),   x_{k+1} = φ x_k + w_k,   φ = exp(−Δt/τ),   Var w = σ²(1 − φ²),
// whose transition is decoupled from every other state, so the M-step is
// closed-form in the smoothed moments
//   a_k = E[x_k² | Y] = x̂_k² + P_k,   b_k = E[x_{k+1} x_k | Y] = x̂_{k+1} x̂_k + P_{k+1,k}
//   σ̂² = [a₀ + (Σ a_{k+1} − 2φ Σ b_k + φ² Σ a_k) / (1 − φ²)] / (n + 1).
// All drifts are updated from one forward and one smoother pass; the
// likelihood never falls (Dempster, Laird & Rubin, JRSS B 39(1), 1977). EM
// crawls when the model's σ is far too small (the smoother then follows the
// data little and the missing information is large), so the cycles are
// extrapolated by SQUAREM (Varadhan & Roland, Scand. J. Statist. 35(2), 2008).
// Standard errors come from the observed information: the second difference
// of the forward filter's log-likelihood ℓ (prediction-error decomposition,
// Schweppe, IEEE Trans. IT-11(1), 1965) in ln σ per drift, at the maximum.
//
// Walks. A bias random walk (ḃ = w, E[w²] = K², effects.md) started at zero
// with the run is, sampled at the epochs, x_{k+1} = x_k + w_k with
// Var w_k = K²Δt; its M-step is as closed-form:
//   K̂² = Σ (a_{k+1} − 2 b_k + a_k) / ((n − 1) Δt).
// Over a bench run a walk and the drift of the same axis share the slow
// variance, so a walk is fitted together with its axis' drift σ. Its
// likelihood-ratio statistic is 2(ℓ̂ − ℓ̂₀), with ℓ̂₀ the maximum without the
// walk (the drift σ re-fitted alone): nested, one parameter on its boundary,
// so χ²₁ is conservative (Self & Liang, JASA 82(398), 1987). The fit starts
// from the walk hypothesis: the drift at its a-priori σ and the walk at that
// drift's own short-term level σ√(2/τ) (the Gauss–Markov process's
// rate-random-walk asymptote, IEEE Std 952-1997 annex C). A walk whose first
// EM step falls below that start is one the run does not tell from the
// drift: it is dropped from the fit without costing it further passes.
//
// Second-order pairs. The catalogue's pair ẋ = (−α I + β J) x + w (effects.md,
// error_model.h) sampled at the epochs is x_{k+1} = Φ x_k + w_k with
// Φ = ρ [cos βΔt −sin βΔt; sin βΔt cos βΔt], ρ = e^{−αΔt}, Var w = σ₂²(1 − ρ²) I.
// With Φ = [a −b; b a] and the smoothed pair moments S₀₀ = Σ E[x_k x_kᵀ],
// S₁₀ = Σ E[x_{k+1} x_kᵀ], S₁₁ = Σ E[x_{k+1} x_{k+1}ᵀ] (k = 0 … n−2), the
// expected complete-data log-likelihood −(n−1) ln q − Σ E|x_{k+1} − Φx_k|²/(2q)
// is maximised by
//   a = tr S₁₀ / tr S₀₀,   b = (S₁₀[1,0] − S₁₀[0,1]) / tr S₀₀,
//   q = (tr S₁₁ − 2(a tr S₁₀ + b (S₁₀[1,0] − S₁₀[0,1])) + (a² + b²) tr S₀₀) / (2(n − 1)),
// whence ρ = √(a² + b²), α = −ln ρ / Δt, β = |atan2(b, a)| / Δt, σ₂² = q / (1 − ρ²)
// (the rotation-constrained AR(1) regression; Shumway & Stoffer §6.3 for the
// unconstrained one). The pair is fitted with its axis' drift σ, screened by
// its first EM step from each starting period, and tested as the walk is,
// 2(ℓ̂ − ℓ̂₀) with three parameters of its own; its errors come from the
// observed information of the four (drift σ, σ₂, α, β) jointly.
#pragma once

#include <absl/status/statusor.h>

#include <Eigen/Core>
#include <array>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/filter/forward_filter.h"
#include "insdiag/engine/ident/drift_ceiling.h"
#include "insdiag/engine/model/drift_axis.h"
#include "insdiag/engine/model/error_model.h"
#include "insdiag/engine/parameter_estimate.h"

namespace insdiag::engine::ident {

struct DriftLikelihoodOptions {
  // EM steps at most (each a forward and a smoother pass).
  int max_iterations = 30;
  // Iterations stop when no ln σ moves by more than this (1%: a tenth of the
  // smallest standard error a bench run gives a drift's σ).
  double log_tolerance = 0.01;
  // …or when the log-likelihood has this little left to gain: the last
  // cycle's gain and its geometric extrapolation from the cycle before
  // (Aitken's Δ², as EM converges linearly; McLachlan & Krishnan, The EM
  // Algorithm and Extensions, 2nd ed., §4.9) both below it. ℓ within 0.01
  // of its maximum puts the estimate within √(2 · 0.01) = 0.14 standard
  // errors of it (ℓ quadratic there), and moves a likelihood-ratio
  // statistic by 0.02. A parameter the run hardly tells, whose ln σ wanders
  // along a flat likelihood by more than `log_tolerance` a step, then stops
  // costing passes.
  double likelihood_tolerance = 0.01;
  // Step of the second difference in ln σ.
  double curvature_step = 0.15;
  // Where the standard errors' observed information comes from: the second
  // differences of ℓ (r(r + 1) forward passes for a block of r parameters,
  // 2 for one), or the smoother's moments by Oakes' identity (2r + 1
  // forward and smoother passes over every parameter at once; ident/
  // drift_em.h, Maximiser::MomentInformation). Measured, not adopted
  // (docs/PERFORMANCE.md): as many passes cost more, each with a smoother.
  enum class Information { kSecondDifferences, kSmootherMoments };
  Information information = Information::kSecondDifferences;
  // Step in the ln of each parameter of the smoother's moments' central
  // difference (the missing information's).
  double moment_information_step = 1e-3;
  // Starting periods of a second-order pair's fit [s] (its decay time starts
  // at the period): over a few hours the likelihood in the period has a
  // local maximum near each multiple of the true one, so EM starts from a
  // grid and each axis keeps the start its first step favours.
  std::vector<double> second_order_start_periods_s = {200.0, 600.0, 1800.0};
  // EM steps at most for the joint fit of the kept pairs: past them the
  // statistic is a lower bound (EM's likelihood only rises), which keeps the
  // test conservative, and a pair the screen kept by chance costs no more.
  int second_order_max_iterations = 12;
};

// A drift whose likelihood estimate the raw samples refuted, and the value
// the model holds instead.
struct HeldDrift {
  DriftAxis drift;
  GaussMarkov estimate;          // the innovations' maximum, beyond the ceiling
  DriftCeilings::Excess excess;  // how far beyond, and at which cluster time
  GaussMarkov held;              // the a-priori value, within the ceiling
};

// A random structure fitted with its axis' drift σ: a bias random walk or a
// second-order Markov pair.
struct StructureEstimate {
  DriftAxis drift;
  std::string effect;              // "gyro_bias_rw.z", "gyro_bias_second_order.y"
  ModelEffect fitted;              // the effect with its identified parameters
  // Method "ML": K (<effect>.density) of a walk; σ₂, τ₂ = 1/α and the period
  // 2π/β (<effect>.sigma, .tau, .period) of a second-order pair. The first
  // is the structure's magnitude.
  std::vector<ParameterEstimate> parameters;
  ParameterEstimate drift_sigma;   // the axis' drift σ fitted with it (method "ML")
  double log_likelihood_without = 0.0;  // ℓ̂₀: the maximum without the structure
  double statistic = 0.0;          // 2(ℓ̂ − ℓ̂₀)
  int dof = 1;                     // the structure's own parameters
  int starts = 1;                  // starting points the screen searched (a pair's periods)
  // A structure whose fit, with its drift, the raw samples refuse
  // (drift_ceiling.h): how far beyond their ceiling. It is not the unit's,
  // whatever 2Δℓ says.
  std::optional<DriftCeilings::Excess> refused_by_raw_samples;
};

// A structure's p-value of `statistic`: χ² with `dof`, Bonferroni over the
// `starts` its fit searched (at most 1).
double StructurePValue(double statistic, int dof, int starts);
// The nested test's: its statistic on the structure's own parameters.
double NestedPValue(const StructureEstimate& s);

struct DriftLikelihoodResult {
  ErrorModel model;                           // the model with the identified σ (and walks)
  std::vector<ParameterEstimate> identified;  // method "ML": .sigma of each selected drift, .density of each walk
  std::vector<StructureEstimate> structures;  // the walks or pairs kept after the screen
  // Structure tests: the axes the screen tried (selected, with a drift, and
  // no such structure in the model); those not in `structures` its first EM
  // step shrank.
  DriftSelection screened;
  // Selected drifts whose likelihood is flat in σ (the run cannot tell it);
  // the model keeps their values.
  std::vector<std::string> not_identifiable;
  // Selected drifts whose estimate the raw samples refuted (in the order found).
  std::vector<HeldDrift> held_by_raw_samples;
  double log_likelihood_before = 0.0;  // ℓ of the model the identification was given
  double log_likelihood_after = 0.0;   // ℓ of `model`
  int iterations = 0;
  int filter_passes = 0;
  bool converged = false;
};

// Identifies σ of the selected drifts of `model` on `run`, and τ too of
// those in `tau_too` (where the model's τ is a placeholder no datasheet
// states: the joint M-step is the AR(1) regression φ̂ = Σ b_k / Σ a_k,
// q̂ = Σ (a_{k+1} − 2φ̂ b_k + φ̂² a_k) / (n − 1), σ̂² = q̂ / (1 − φ̂²),
// τ̂ = −Δt / ln φ̂; Shumway & Stoffer §6.3). `a_priori` gives the values the
// report lists against the estimates. A drift whose estimate `ceilings`
// (what the run's raw samples allow; empty, every drift) refuse is held at
// its `a_priori` value (lowered to the ceiling where that too is refused),
// listed in `held_by_raw_samples`, and the other drifts fitted again beside
// it: what its wandering absorbed, they must not keep. With nothing to
// identify it runs no filter pass and returns the model as it is.
absl::StatusOr<DriftLikelihoodResult> IdentifyDriftsByLikelihood(const EpochRun& run, const ErrorModel& model,
                                                                 const ErrorModel& a_priori,
                                                                 const DriftSelection& which,
                                                                 const DriftSelection& tau_too,
                                                                 const DriftCeilings& ceilings,
                                                                 const DriftLikelihoodOptions& options = {});

// The observed information −∂²ℓ/∂θ∂θᵀ of `model` on `run`, θ the ln of the
// named parameters ("gyro_bias_gm.x.sigma", "…tau", "acc_bias_rw.y.density",
// "gyro_bias_second_order.z.sigma", "….alpha", "….beta"; a τ with
// its σ, a pair's α and β with its σ₂), by `options.information`, with the
// passes it took: what the identification's errors come from, for tests and
// measurements.
struct DriftInformation {
  Eigen::MatrixXd information;  // in the order of the names
  int filter_passes = 0;        // forward passes, or forward and smoother passes
};
absl::StatusOr<DriftInformation> ObservedDriftInformation(const EpochRun& run, const ErrorModel& model,
                                                          const std::vector<std::string>& names,
                                                          const DriftLikelihoodOptions& options = {});

// Where EM starts when the drifts may be far from the model's values.
struct DriftStartOptions {
  // EM from these multiples of the model's τ (σ at the model's), besides
  // the model's values.
  std::array<double, 2> tau_factors = {0.1, 10.0};
  // And from the best point of a coarse grid of the likelihood, searched one
  // drift at a time: σ at these multiples of the model's, τ at
  // `grid_tau_points` log-spaced from two update intervals to the run's
  // length. EM creeps from a σ far below the truth (the smoothed drift is
  // held at its small prior, so each step moves σ little), and from a τ on
  // the far side of the likelihood's ridge; the grid needs no start.
  std::array<double, 6> grid_sigma_factors = {0.1, 0.3, 1.0, 3.0, 10.0, 30.0};
  int grid_tau_points = 5;  // 0: no grid start
  // And from the drifts the static segments' Allan curve gives
  // (ErrorModelFromAllan), where the model's are a class prior the run may
  // be far from: every other start climbs from the prior's side, and the
  // grid weighs one drift at a time beside the others' prior values, so a
  // unit far from its label's drifts on every axis can end on a local
  // maximum well below its own drifts'.
  std::optional<std::array<GaussMarkov, DriftAxis::kCount>> raw_sample_drifts;
};

// σ and τ of the selected drifts from several starting points (`starts`),
// the fit with the highest likelihood kept, then axis by axis another
// start's drift where it raises the likelihood, and EM again from that
// combination. Over a few correlation times the likelihood in (σ, τ) has
// more than one maximum along its ridge, and EM climbs the one nearest its
// start: a unit whose drift is far from its type's nominal model (τ a
// tenth, σ ten times) needs a start on its side of the ridge. The result's
// `iterations` and `filter_passes` count every start and the grid.
absl::StatusOr<DriftLikelihoodResult> IdentifyDriftsFromStarts(const EpochRun& run, const ErrorModel& model,
                                                               const ErrorModel& a_priori,
                                                               const DriftSelection& which,
                                                               const DriftStartOptions& starts,
                                                               const DriftCeilings& ceilings,
                                                               const DriftLikelihoodOptions& options = {});

// σ (and τ where `tau_too`) of the selected drifts by EM from the best
// point of DriftStartOptions' grid rather than from the model's values: for
// a model whose drifts are a class prior (a unit type's nominal, an Allan
// fit), which EM started there creeps away from (a σ tripled stays within
// 15 % of the prior after six steps). `log_likelihood_before` is the
// model's, and `filter_passes` counts the grid's.
absl::StatusOr<DriftLikelihoodResult> IdentifyDriftsFromGrid(const EpochRun& run, const ErrorModel& model,
                                                             const ErrorModel& a_priori, const DriftSelection& which,
                                                             const DriftSelection& tau_too,
                                                             const DriftStartOptions& starts,
                                                             const DriftCeilings& ceilings,
                                                             const DriftLikelihoodOptions& options = {});

// The standard errors of `fit`'s drift estimates made consistent with the
// likelihood ratio against `reference` (the model's values before the fit):
// per drift, the Wald statistic W = Σ ((ln v̂ − ln v₀)/SE(ln v̂))² over its σ
// and τ is set against 2Δℓ of the fit with that drift put back to
// `reference`'s values, and where W exceeds it the drift's SEs (and 95 %
// intervals) are widened by √(W/2Δℓ) — test-based standard errors
// (Miettinen, Am. J. Epidemiol. 103(2), 1976). Along a drift's σ–τ ridge the
// curvature at the estimate says little about how far the likelihood stays
// flat: one hour of a 30-minute drift gave σ and τ 6.6 and 5.9 SE from the
// datasheet's values where 2Δℓ between the two points was 9.0 (the SEs
// widen 3 ×). 2Δℓ is floored at χ²'s median for the drift's parameter count.
// Never narrows an SE. One filter pass per drift. Returns the names of the
// drifts widened.
absl::StatusOr<std::vector<std::string>> WidenErrorsToTheLikelihoodRatio(const EpochRun& run,
                                                                         const ErrorModel& reference,
                                                                         DriftLikelihoodResult& fit);

// The drifts of `fit` (a fit from `model`) worth their parameters by BIC,
// by backward elimination in the joint fit: each drift's σ and τ must raise
// the log-likelihood of the fit with every other kept drift by more than
// ln N a parameter (2Δℓ > k ln N, N the run's scalar updates; Schwarz
// 1978); the least worth is put
// back to the model's values and the rest weighed again, until every kept
// drift is worth its cost. The result holds those drifts only, its
// identified parameters and likelihood theirs. Weighed in the joint fit, not
// alone in `model`: one axis's drift far from the model's swamps the
// innovations, and another axis's drift tried alone beside that misfit
// looks worthless, then shows as steps and walks once the first is taken. A
// run tells some axes' drifts and not others, and a parameter re-tuned
// without cause costs the competition its ln N. One filter pass per kept
// drift per round and one for `model`.
absl::StatusOr<DriftLikelihoodResult> KeepDriftsWorthTheirParameters(const EpochRun& run,
                                                                     const ErrorModel& model,
                                                                     DriftLikelihoodResult fit);

// Fits a bias random walk on each selected axis that has a drift and no walk
// in `model`, each with its axis' drift σ (header), and tests each against
// the model without it. The result's model holds the walks that the first
// EM step kept; `structures` their estimates and statistics — with standard
// errors for those whose nested test passes at `screen_alpha` (the others'
// are NaN: their information would cost passes for nothing).
absl::StatusOr<DriftLikelihoodResult> IdentifyWalksByLikelihood(const EpochRun& run, const ErrorModel& model,
                                                                const ErrorModel& a_priori,
                                                                const DriftSelection& axes, double screen_alpha,
                                                                const DriftCeilings& ceilings,
                                                                const DriftLikelihoodOptions& options = {});

// Fits a second-order Markov pair (catalogue: gyro_bias_second_order,
// acc_bias_second_order) on each selected axis that has a drift and no pair
// in `model`, each with its axis' drift σ, from each starting period of the
// options; keeps the axes whose first EM step lets the pair grow, fits them
// jointly and tests each against the model without it (header: Second-order
// pairs). `screen_alpha` as for the walks, over the starting periods
// (Bonferroni).
absl::StatusOr<DriftLikelihoodResult> IdentifySecondOrdersByLikelihood(const EpochRun& run, const ErrorModel& model,
                                                                       const ErrorModel& a_priori,
                                                                       const DriftSelection& axes,
                                                                       double screen_alpha,
                                                                       const DriftCeilings& ceilings,
                                                                       const DriftLikelihoodOptions& options = {});

// The covariance of a fitted structure's (ln σ of its drift, then its own
// ln parameters) from their observed information at the maximum: the
// inverse where the information is positive definite. Where it is not and
// the likelihood is flat in the drift's ln σ — the σ fell to its boundary
// (σ → 0 next to a walk that carries the slow variance) — the σ is held
// there and the structure's errors are those of its own block (Self &
// Liang, J. Am. Stat. Assoc. 82(398), 1987); the σ's stays unknown
// (infinite). Where the σ is not flat the lack of concavity is the
// structure's own and every error stays unknown: conditioning on the σ
// would understate them.
Eigen::MatrixXd StructureCovariance(const Eigen::MatrixXd& information);

}  // namespace insdiag::engine::ident
