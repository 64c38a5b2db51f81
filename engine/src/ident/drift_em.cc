#include "ident/drift_em.h"

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

namespace insdiag::engine::ident::drift_em {
namespace {

// The M-step of a second-order pair (header: Second-order pairs) from its
// smoothed means (columns i, i+1 of x) and moments; false when the
// regression leaves the stationary region (ρ ≥ 1) or has no variance.
struct PairStep {
  double sigma = 0.0, alpha_per_s = 0.0, beta_rad_s = 0.0;
};
bool PairMStep(const Eigen::MatrixXd& x, int i,
               const Eigen::Matrix<double, Eigen::Dynamic, 7>& moments, double dt, PairStep& out) {
  const auto K = x.rows();
  Eigen::Matrix2d S00 = Eigen::Matrix2d::Zero(), S11 = Eigen::Matrix2d::Zero(),
                  S10 = Eigen::Matrix2d::Zero();
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
  const double q = (S11.trace() - 2.0 * (a * tr10 + b * skew) + rho2 * tr00) /
                   (2.0 * static_cast<double>(K - 1));
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

// The complete-data log-likelihood's derivatives (drift_em.h:
// MomentInformation). Each state's Q is its own: the drift, walk and pair
// states have transitions of their own (seed eq. 5 for the drift; the
// header's walk and pair), so Q is a sum over the states and its Hessian in
// θ′ is block-diagonal by state. Constants dropped; n epochs, n − 1
// transitions; the smoothed sums are those of the M-step.

// A scalar state's smoothed sums: a₀ = E[x₀²], Σ a_k and Σ a_{k+1} over the
// transitions, Σ b_k (header: a_k, b_k).
struct ScalarSums {
  double a0 = 0.0, a_from = 0.0, a_to = 0.0, b = 0.0;
};
ScalarSums SumsOfState(const SmoothedPass& sm, int state, int K) {
  ScalarSums out;
  for (int k = 0; k + 1 < K; ++k) {
    const double x0 = sm.x(k, state), x1 = sm.x(k + 1, state);
    out.a_from += x0 * x0 + sm.variance(k, state);
    out.a_to += x1 * x1 + sm.variance(k + 1, state);
    out.b += x1 * x0 + sm.lag_one_covariance(k, state);
  }
  out.a0 = sm.x(0, state) * sm.x(0, state) + sm.variance(0, state);
  return out;
}

// A pair's smoothed sums (header: Second-order pairs): T₀ = tr E[x₀x₀ᵀ],
// tr S₀₀, tr S₁₁, tr S₁₀ and S₁₀[1,0] − S₁₀[0,1].
struct PairSums {
  double t0 = 0.0, t00 = 0.0, t11 = 0.0, tr10 = 0.0, skew = 0.0;
};
PairSums SumsOfPair(const Eigen::MatrixXd& x, int i,
                    const Eigen::Matrix<double, Eigen::Dynamic, 7>& moments) {
  const auto K = x.rows();
  auto trace_second = [&](Eigen::Index k) {
    return x(k, i) * x(k, i) + x(k, i + 1) * x(k, i + 1) + moments(k, 0) + moments(k, 2);
  };
  PairSums out;
  out.t0 = trace_second(0);
  for (Eigen::Index k = 0; k + 1 < K; ++k) {
    out.t00 += trace_second(k);
    out.t11 += trace_second(k + 1);
    out.tr10 += x(k + 1, i) * x(k, i) + moments(k, 3) + x(k + 1, i + 1) * x(k, i + 1) + moments(k, 6);
    out.skew += x(k + 1, i + 1) * x(k, i) + moments(k, 5) - (x(k + 1, i) * x(k, i + 1) + moments(k, 4));
  }
  return out;
}

// A first-order drift (x₀ ~ N(0, σ²), x_{k+1} = φx_k + w_k, Var w = σ²u,
// u = 1 − φ², φ = e^{−Δt/τ}): with S(φ) = Σa_{k+1} − 2φΣb_k + φ²Σa_k and
// g = S/u,
//   Q = −n s − (a₀ + g) e^{−2s}/2 − (n − 1)/2 · ln u,   s = ln σ,
//   Q_s = −n + (a₀ + g)/σ²,   Q_ss = −2(a₀ + g)/σ²,   Q_sφ = g′/σ²,
//   Q_φ = (n − 1)φ/u − g′/(2σ²),   Q_φφ = (n − 1)(1 + φ²)/u² − g″/(2σ²),
//   g′ = S′/u + 2φS/u²,   g″ = S″/u + 4φS′/u² + 2S/u² + 8φ²S/u³,
//   S′ = 2(φΣa_k − Σb_k),   S″ = 2Σa_k;
// in t = ln τ through φ_t = φΔt/τ, φ_tt = φ_t(Δt/τ − 1):
//   Q_t = Q_φ φ_t,   Q_tt = Q_φφ φ_t² + Q_φ φ_tt,   Q_st = Q_sφ φ_t.
// Q_s and Q_t are the score of the branch not adopted (Fisher's identity).
struct TwoDerivatives {
  Eigen::Vector2d score = Eigen::Vector2d::Zero();
  Eigen::Matrix2d hessian = Eigen::Matrix2d::Zero();
};
TwoDerivatives GaussMarkovDerivatives(double sigma, double tau_s, const ScalarSums& z, int n,
                                      double dt) {
  const double phi = std::exp(-dt / tau_s), u = 1.0 - phi * phi, s2 = sigma * sigma;
  const double S = z.a_to - 2.0 * phi * z.b + phi * phi * z.a_from;
  const double dS = 2.0 * (phi * z.a_from - z.b), d2S = 2.0 * z.a_from;
  const double g = S / u;
  const double dg = dS / u + 2.0 * phi * S / (u * u);
  const double d2g = d2S / u + 4.0 * phi * dS / (u * u) + 2.0 * S / (u * u) +
                     8.0 * phi * phi * S / (u * u * u);
  const double transitions = n - 1.0;
  const double q_s = -n + (z.a0 + g) / s2, q_ss = -2.0 * (z.a0 + g) / s2, q_sphi = dg / s2;
  const double q_phi = transitions * phi / u - dg / (2.0 * s2);
  const double q_phiphi = transitions * (1.0 + phi * phi) / (u * u) - d2g / (2.0 * s2);
  const double phi_t = phi * dt / tau_s, phi_tt = phi_t * (dt / tau_s - 1.0);
  TwoDerivatives out;
  out.score << q_s, q_phi * phi_t;
  out.hessian << q_ss, q_sphi * phi_t, q_sphi * phi_t, q_phiphi * phi_t * phi_t + q_phi * phi_tt;
  return out;
}

// A pair (x₀ ~ N(0, σ₂²I), x_{k+1} = ρR(ω)x_k + w_k, Var w = σ₂²uI,
// u = 1 − ρ², ρ = e^{−αΔt}, ω = βΔt): with C(ω) = cos ω tr S₁₀ +
// sin ω (S₁₀[1,0] − S₁₀[0,1]), W = tr S₁₁ − 2ρC + ρ² tr S₀₀ = Σ E|x_{k+1} −
// Φx_k|² and G = W/u,
//   Q = −2n s₂ − (T₀ + G) e^{−2s₂}/2 − (n − 1) ln u,   s₂ = ln σ₂,
//   Q_s = −2n + (T₀ + G)/σ₂²,   Q_ss = −2(T₀ + G)/σ₂²,
//   Q_sρ = G_ρ/σ₂²,   Q_sω = G_ω/σ₂²,
//   Q_ρ = 2(n − 1)ρ/u − G_ρ/(2σ₂²),   Q_ω = −G_ω/(2σ₂²),
//   Q_ρρ = 2(n − 1)(1 + ρ²)/u² − G_ρρ/(2σ₂²),   Q_ρω = −G_ρω/(2σ₂²),   Q_ωω = −G_ωω/(2σ₂²),
//   G_ρ = W_ρ/u + 2ρW/u²,   G_ρρ = W_ρρ/u + 4ρW_ρ/u² + 2W/u² + 8ρ²W/u³,
//   G_ω = W_ω/u,   G_ωω = W_ωω/u,   G_ρω = W_ρω/u + 2ρW_ω/u²,
//   W_ρ = 2(ρ tr S₀₀ − C),   W_ρρ = 2 tr S₀₀,   W_ω = −2ρC′,   W_ωω = 2ρC,   W_ρω = −2C′;
// in (s₂, ln α, ln β) through ρ_a = −αΔtρ, ρ_aa = ρ_a(1 − αΔt), ω_b = ω_bb = ω.
struct ThreeDerivatives {
  Eigen::Vector3d score = Eigen::Vector3d::Zero();
  Eigen::Matrix3d hessian = Eigen::Matrix3d::Zero();
};
ThreeDerivatives PairDerivatives(double sigma, double alpha_per_s, double beta_rad_s,
                                 const PairSums& z, int n, double dt) {
  const double rho = std::exp(-alpha_per_s * dt), u = 1.0 - rho * rho, s2 = sigma * sigma;
  const double w = beta_rad_s * dt;
  const double C = std::cos(w) * z.tr10 + std::sin(w) * z.skew;
  const double dC = -std::sin(w) * z.tr10 + std::cos(w) * z.skew;
  const double W = z.t11 - 2.0 * rho * C + rho * rho * z.t00;
  const double W_r = 2.0 * (rho * z.t00 - C), W_rr = 2.0 * z.t00;
  const double W_w = -2.0 * rho * dC, W_ww = 2.0 * rho * C, W_rw = -2.0 * dC;
  const double G = W / u;
  const double G_r = W_r / u + 2.0 * rho * W / (u * u);
  const double G_rr = W_rr / u + 4.0 * rho * W_r / (u * u) + 2.0 * W / (u * u) +
                      8.0 * rho * rho * W / (u * u * u);
  const double G_w = W_w / u, G_ww = W_ww / u, G_rw = W_rw / u + 2.0 * rho * W_w / (u * u);
  const double transitions = n - 1.0;
  const double q_s = -2.0 * n + (z.t0 + G) / s2, q_ss = -2.0 * (z.t0 + G) / s2;
  const double q_sr = G_r / s2, q_sw = G_w / s2;
  const double q_r = 2.0 * transitions * rho / u - G_r / (2.0 * s2);
  const double q_w = -G_w / (2.0 * s2);
  const double q_rr = 2.0 * transitions * (1.0 + rho * rho) / (u * u) - G_rr / (2.0 * s2);
  const double q_rw = -G_rw / (2.0 * s2), q_ww = -G_ww / (2.0 * s2);
  const double rho_a = -alpha_per_s * dt * rho, rho_aa = rho_a * (1.0 - alpha_per_s * dt);
  const double w_b = w, w_bb = w;
  ThreeDerivatives out;
  out.score << q_s, q_r * rho_a, q_w * w_b;
  out.hessian(0, 0) = q_ss;
  out.hessian(0, 1) = out.hessian(1, 0) = q_sr * rho_a;
  out.hessian(0, 2) = out.hessian(2, 0) = q_sw * w_b;
  out.hessian(1, 1) = q_rr * rho_a * rho_a + q_r * rho_aa;
  out.hessian(1, 2) = out.hessian(2, 1) = q_rw * rho_a * w_b;
  out.hessian(2, 2) = q_ww * w_b * w_b + q_w * w_bb;
  return out;
}

}  // namespace

int EffectOf(const ErrorModel& m, const std::string& name) {
  auto terms = ParseEffectSelector(name);
  return terms.ok() ? m.FindEffect(terms->front()) : -1;
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

Maximiser::Maximiser(const EpochRun& run, ErrorModel model, std::vector<Parameter> parameters,
                     const DriftLikelihoodOptions& options, DriftLikelihoodResult& out)
    : run_(run),
      model_(std::move(model)),
      layout_(model_),
      parameters_(std::move(parameters)),
      options_(options),
      out_(out) {
  for (const Parameter& p : parameters_) {
    if (p.kind == Kind::kTau) tau_free_.Set(p.drift);
    if (p.kind == Kind::kPairSigma) {
      pair_slot_[static_cast<size_t>(p.drift.Index())] =
          static_cast<int>(smoother_.pair_states.size());
      smoother_.pair_states.push_back(layout_.EffectOffset(PairEffectOf(model_, p.drift)));
    }
  }
}

Eigen::VectorXd Maximiser::Start() const {
  Eigen::VectorXd theta(static_cast<Eigen::Index>(parameters_.size()));
  for (size_t j = 0; j < parameters_.size(); ++j)
    theta[static_cast<Eigen::Index>(j)] = std::log(ValueOf(model_, parameters_[j]));
  return theta;
}

ErrorModel Maximiser::ModelOf(const Eigen::VectorXd& theta) const {
  ErrorModel m = model_;
  for (size_t j = 0; j < parameters_.size(); ++j)
    ValueOf(m, parameters_[j]) = std::exp(theta[static_cast<Eigen::Index>(j)]);
  return m;
}

absl::StatusOr<double> Maximiser::LogLikelihood(const ErrorModel& m) {
  ++out_.filter_passes;
  auto fw = RunForwardFilter(run_, m);
  if (!fw.ok()) return fw.status();
  return fw->log_likelihood;
}

absl::StatusOr<std::vector<double>> Maximiser::LogLikelihoods(
    const std::vector<Eigen::VectorXd>& probes) {
  out_.filter_passes += static_cast<int>(probes.size());
  const auto values =
      numerics::ParallelMap(probes.size(), [&](std::size_t i) -> absl::StatusOr<double> {
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

absl::StatusOr<Maximiser::Smoothed> Maximiser::SmoothedAt(const Eigen::VectorXd& theta) const {
  auto fw = RunForwardFilter(run_, ModelOf(theta));
  if (!fw.ok()) return fw.status();
  const int K = fw->epochs();
  if (K < 3)
    return absl::InvalidArgumentError("drift likelihood: the run has fewer than three epochs");
  auto sm = RunSmoother(*fw, smoother_);
  if (!sm.ok()) return sm.status();
  const double dt = (fw->epoch_time_s.back() - fw->epoch_time_s.front()) / (K - 1);
  return Smoothed{fw->log_likelihood, *std::move(sm), K, dt};
}

absl::StatusOr<Maximiser::Step> Maximiser::EmStep(const Eigen::VectorXd& theta) {
  ++out_.filter_passes;
  auto smoothed = SmoothedAt(theta);
  if (!smoothed.ok()) return smoothed.status();
  const SmoothedPass* sm = &smoothed->pass;
  const int K = smoothed->epochs;
  const double dt = smoothed->dt;
  Step step{smoothed->log_likelihood, theta};
  for (size_t j = 0; j < parameters_.size(); ++j) {
    const Parameter& p = parameters_[j];
    const auto i = static_cast<Eigen::Index>(j);
    if (IsPair(p.kind)) {
      const int slot = pair_slot_[static_cast<size_t>(p.drift.Index())];
      PairStep pair;
      if (!PairMStep(sm->x, smoother_.pair_states[static_cast<size_t>(slot)],
                     sm->pair_moments[static_cast<size_t>(slot)], dt, pair)) {
        continue;
      }
      step.next[i] = std::log(p.kind == Kind::kPairSigma       ? pair.sigma
                              : p.kind == Kind::kPairDecayRate ? pair.alpha_per_s
                                                               : pair.beta_rad_s);
      continue;
    }
    const bool walk = p.kind == Kind::kWalk;
    const int bias = p.drift.sensor == Sensor::kGyro ? layout_.gyro_bias() : layout_.acc_bias();
    const int state =
        walk ? layout_.EffectOffset(WalkEffectOf(model_, p.drift)) : bias + p.drift.axis;
    const ScalarSums sums = SumsOfState(*sm, state, K);
    const double a0 = sums.a0, a_from = sums.a_from, a_to = sums.a_to, b = sums.b;
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
      const double sigma2 =
          (a0 + (a_to - 2.0 * phi * b + phi * phi * a_from) / (1.0 - phi * phi)) / K;  // σ̂²
      if (sigma2 > 0.0) step.next[i] = 0.5 * std::log(sigma2);
    }
  }
  return step;
}

absl::StatusOr<Eigen::VectorXd> Maximiser::Maximise(Eigen::VectorXd theta,
                                                    double* first_likelihood) {
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

absl::StatusOr<double> Maximiser::Information(const Eigen::VectorXd& theta, Eigen::Index j,
                                              double l0) {
  const double h = options_.curvature_step;
  std::vector<Eigen::VectorXd> probes(2, theta);
  probes[0][j] += h;
  probes[1][j] -= h;
  auto shifted = LogLikelihoods(probes);
  if (!shifted.ok()) return shifted.status();
  return -((*shifted)[0] - 2.0 * l0 + (*shifted)[1]) / (h * h);
}

absl::StatusOr<Eigen::MatrixXd> Maximiser::BlockInformation(const Eigen::VectorXd& theta,
                                                            const std::vector<Eigen::Index>& at,
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

Eigen::Index Maximiser::IndexOf(Kind kind, DriftAxis drift) const {
  for (size_t j = 0; j < parameters_.size(); ++j) {
    if (parameters_[j].kind == kind && parameters_[j].drift == drift) return static_cast<Eigen::Index>(j);
  }
  return -1;
}

absl::StatusOr<Maximiser::CompleteDerivatives> Maximiser::CompleteDataDerivatives(
    const Eigen::VectorXd& smoothed_at, const Eigen::VectorXd& theta_prime, bool hessian) const {
  auto smoothed = SmoothedAt(smoothed_at);
  if (!smoothed.ok()) return smoothed.status();
  const SmoothedPass* sm = &smoothed->pass;
  const int K = smoothed->epochs;
  const double dt = smoothed->dt;
  const ErrorModel at = ModelOf(theta_prime);
  const auto m = static_cast<Eigen::Index>(parameters_.size());
  CompleteDerivatives out{Eigen::VectorXd::Zero(m), Eigen::MatrixXd()};
  if (hessian) out.hessian = Eigen::MatrixXd::Zero(m, m);
  for (size_t j = 0; j < parameters_.size(); ++j) {
    const Parameter& p = parameters_[j];
    const auto i = static_cast<Eigen::Index>(j);
    switch (p.kind) {
      case Kind::kSigma: {  // the drift, with its τ where that is a parameter too
        const int state =
            (p.drift.sensor == Sensor::kGyro ? layout_.gyro_bias() : layout_.acc_bias()) + p.drift.axis;
        const GaussMarkov& drift = DriftOf(at, p.drift);
        const TwoDerivatives d =
            GaussMarkovDerivatives(drift.sigma, drift.tau_s, SumsOfState(*sm, state, K), K, dt);
        const Eigen::Index t = IndexOf(Kind::kTau, p.drift);
        out.score[i] = d.score[0];
        if (t >= 0) out.score[t] = d.score[1];
        if (hessian) {
          out.hessian(i, i) = d.hessian(0, 0);
          if (t >= 0) {
            out.hessian(i, t) = out.hessian(t, i) = d.hessian(0, 1);
            out.hessian(t, t) = d.hessian(1, 1);
          }
        }
        break;
      }
      case Kind::kWalk: {
        // Started at zero with the run (x₀ = 0), x_{k+1} = x_k + w_k,
        // Var w = K²Δt: with D = Σ (a_{k+1} − 2b_k + a_k) and κ = ln K,
        //   Q = −(n − 1)κ − D e^{−2κ}/(2Δt),
        //   Q_κ = −(n − 1) + D/(K²Δt),   Q_κκ = −2D/(K²Δt).
        const ScalarSums z = SumsOfState(*sm, layout_.EffectOffset(WalkEffectOf(model_, p.drift)), K);
        const double k = ValueOf(at, p);
        const double d = (z.a_to - 2.0 * z.b + z.a_from) / (k * k * dt);
        out.score[i] = -(K - 1.0) + d;
        if (hessian) out.hessian(i, i) = -2.0 * d;
        break;
      }
      case Kind::kPairSigma: {  // with the pair's α and β
        const int slot = pair_slot_[static_cast<size_t>(p.drift.Index())];
        const ModelEffect& e = at.effects[static_cast<size_t>(PairEffectOf(model_, p.drift))];
        const ThreeDerivatives d = PairDerivatives(
            e.second_order_sigma, e.second_order_alpha_per_s, e.second_order_beta_rad_s,
            SumsOfPair(sm->x, smoother_.pair_states[static_cast<size_t>(slot)],
                       sm->pair_moments[static_cast<size_t>(slot)]),
            K, dt);
        const std::array<Eigen::Index, 3> index = {i, IndexOf(Kind::kPairDecayRate, p.drift),
                                                   IndexOf(Kind::kPairFrequency, p.drift)};
        for (size_t a = 0; a < 3; ++a) {
          if (index[a] < 0) continue;
          out.score[index[a]] = d.score[static_cast<Eigen::Index>(a)];
          if (!hessian) continue;
          for (size_t b = 0; b < 3; ++b) {
            if (index[b] >= 0)
              out.hessian(index[a], index[b]) =
                  d.hessian(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b));
          }
        }
        break;
      }
      case Kind::kTau:
      case Kind::kPairDecayRate:
      case Kind::kPairFrequency:
        break;  // with their σ's
    }
  }
  return out;
}

absl::StatusOr<Eigen::MatrixXd> Maximiser::MomentInformation(const Eigen::VectorXd& theta,
                                                             const std::vector<Eigen::Index>& at) {
  const double h = options_.moment_information_step;
  const auto r = static_cast<Eigen::Index>(at.size());
  // Pass 0 at θ (the complete information), passes 1 + 2a and 2 + 2a with
  // the smoother at θ ± h e_a; every score at θ′ = θ.
  out_.filter_passes += static_cast<int>(2 * r + 1);
  const auto passes = numerics::ParallelMap(
      static_cast<std::size_t>(2 * r + 1), [&](std::size_t c) -> absl::StatusOr<CompleteDerivatives> {
        Eigen::VectorXd smoothed_at = theta;
        if (c > 0) smoothed_at[at[(c - 1) / 2]] += c % 2 == 1 ? h : -h;
        return CompleteDataDerivatives(smoothed_at, theta, c == 0);
      });
  for (const auto& pass : passes) {
    if (!pass.ok()) return pass.status();
  }
  const CompleteDerivatives& base = *passes[0];
  Eigen::MatrixXd missing(r, r);  // ∂²Q/∂θ′_a ∂θ_b
  for (Eigen::Index b = 0; b < r; ++b) {
    const auto up = static_cast<size_t>(2 * b + 1);
    const Eigen::VectorXd change = (passes[up]->score - passes[up + 1]->score) / (2.0 * h);
    for (Eigen::Index a = 0; a < r; ++a) missing(a, b) = change[at[static_cast<size_t>(a)]];
  }
  Eigen::MatrixXd information(r, r);
  for (Eigen::Index a = 0; a < r; ++a) {
    for (Eigen::Index b = 0; b < r; ++b) {
      information(a, b) = -base.hessian(at[static_cast<size_t>(a)], at[static_cast<size_t>(b)]) -
                          0.5 * (missing(a, b) + missing(b, a));
    }
  }
  return information;
}

absl::Status ValidateOptions(const DriftLikelihoodOptions& options) {
  if (!(options.max_iterations > 0 && options.second_order_max_iterations > 0 &&
        options.log_tolerance > 0.0 && options.likelihood_tolerance > 0.0 &&
        options.curvature_step > 0.0 && options.moment_information_step > 0.0)) {
    return absl::InvalidArgumentError("drift likelihood options out of range");
  }
  return absl::OkStatus();
}

bool HasDrift(const ErrorModel& m, DriftAxis drift) {
  return DriftOf(m, drift).sigma > 0.0 && DriftOf(m, drift).tau_s > 0.0;
}

// Maximises from the model's values into `out` (model, iterations,
// convergence, ℓ at the estimate); `first_likelihood` gets ℓ at the start.
absl::StatusOr<Eigen::VectorXd> FitInto(Maximiser& em, DriftLikelihoodResult& out,
                                        double* first_likelihood) {
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

ParameterEstimate EstimateOf(const Parameter& p, double value, double log_se,
                             const ErrorModel& a_priori) {
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
}  // namespace insdiag::engine::ident::drift_em
