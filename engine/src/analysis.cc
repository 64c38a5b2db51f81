#include "insdiag/engine/analysis.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numbers>
#include <optional>

#include "insdiag/engine/filter/smoother.h"
#include "insdiag/engine/finder/fault_findings.h"
#include "insdiag/engine/finder/score_test.h"
#include "insdiag/engine/ident/retarget.h"
#include "insdiag/engine/stats/distributions.h"
#include <Eigen/Eigenvalues>
#include <memory>

namespace insdiag::engine {
namespace {

void Progress(const AnalysisOptions& o, double fraction, std::string_view stage) {
  if (o.progress) o.progress(fraction, stage);
}

// RMS over the run of every constant term's regressor, per parameter.
std::array<double, 2> RegressorRms(const BenchRun& run, const EffectTerm& term) {
  std::array<double, 2> sum = {0.0, 0.0};
  double values[2];
  const double t0 = run.samples.front().temp_degc;
  for (const ImuSample& s : run.samples) {
    RegressorInputs in;
    in.gyro_rad_s = s.gyro_rad_s;
    in.acc_mps2 = s.acc_mps2;
    in.temperature_delta_degc = run.has_temperature ? s.temp_degc - t0 : 0.0;
    in.yaw_rad = s.ref_rpy_rad.z();
    EvaluateRegressor(term, in, values);
    for (int p = 0; p < term.family->parameters_per_term; ++p) sum[static_cast<size_t>(p)] += values[p] * values[p];
  }
  const double n = static_cast<double>(run.samples.size());
  return {std::sqrt(sum[0] / n), std::sqrt(sum[1] / n)};
}

}  // namespace

absl::Status AnalysisOptions::Validate() const {
  if (auto st = filter.Validate(); !st.ok()) return st;
  if (!(monitor.window_s > 0.0)) return absl::InvalidArgumentError("monitor window must be positive");
  if (!(monitor.family_wise_alpha > 0.0 && monitor.family_wise_alpha < 1.0)) {
    return absl::InvalidArgumentError("family-wise α must be in (0, 1)");
  }
  if (!(diffuse_prior_scale > 0.0)) return absl::InvalidArgumentError("diffuse prior scale must be positive");
  return absl::OkStatus();
}

absl::StatusOr<ErrorModel> APrioriModel(const BenchRun& run, const std::optional<ErrorModel>& nominal,
                                        const ReferenceAccuracy& reference) {
  const Datasheet& d = run.metadata.datasheet;
  ErrorModel model = nominal.value_or(ErrorModel{});
  model.reference = reference;
  std::string missing;
  auto take = [&](const std::optional<double>& value, bool has_nominal, const char* key, auto&& assign) {
    if (value.has_value()) {
      assign(*value);
    } else if (!has_nominal) {
      missing += (missing.empty() ? "" : ", ") + std::string(key);
    }
  };
  const bool n = nominal.has_value();
  take(d.gyro_arw_rad_rts, n, "gyro_arw", [&](double v) { model.gyro.white_noise_density.setConstant(v); });
  take(d.gyro_bias_sigma_rad_s, n, "gyro_bias_sigma", [&](double v) {
    for (auto& b : model.gyro.bias) b.sigma = v;
  });
  take(d.gyro_bias_tau_s, n, "gyro_bias_tau", [&](double v) {
    for (auto& b : model.gyro.bias) b.tau_s = v;
  });
  take(d.acc_vrw_mps_rts, n, "acc_vrw", [&](double v) { model.acc.white_noise_density.setConstant(v); });
  take(d.acc_bias_sigma_mps2, n, "acc_bias_sigma", [&](double v) {
    for (auto& b : model.acc.bias) b.sigma = v;
  });
  take(d.acc_bias_tau_s, n, "acc_bias_tau", [&](double v) {
    for (auto& b : model.acc.bias) b.tau_s = v;
  });
  if (!missing.empty()) {
    return absl::FailedPreconditionError("no a-priori value for " + missing +
                                         ": the run's datasheet lacks it and no nominal model was given");
  }
  return model;
}

// The dominant constant biases removed from `run` (ident/static_constants.h),
// on the Allan analysis's static segments when it ran.
std::vector<ParameterEstimate> RemoveDominantConstants(BenchRun& run, const std::optional<ident::AllanResult>& allan,
                                                       const ErrorModel& a_priori, const AnalysisOptions& options,
                                                       std::vector<std::string>& notes) {
  if (allan.has_value()) {
    return ident::RemoveDominantConstants(run, allan->segments, a_priori, options.dominant_constants, notes);
  }
  auto segments = ident::FindStaticSegments(run, options.allan);
  if (!segments.ok()) return {};
  return ident::RemoveDominantConstants(run, *segments, a_priori, options.dominant_constants, notes);
}

absl::Status AddEffects(const BenchRun& run, const std::vector<std::string>& selectors, double update_interval_s,
                        double diffuse_prior_scale, ErrorModel& model) {
  for (const std::string& selector : selectors) {
    auto terms = ParseEffectSelector(selector);
    if (!terms.ok()) return terms.status();
    auto onset = ParseOnset(selector);
    if (!onset.ok()) return onset.status();
    for (const EffectTerm& term : *terms) {
      if (model.FindEffect(term) >= 0) continue;
      ModelEffect e;
      e.term = term;
      if (term.family->kind == EffectKind::kFault) {
        if (!onset->has_value()) {
          return absl::InvalidArgumentError("effect '" + selector + "' is a fault: name its onset, " + term.Name() +
                                            "@SECONDS, or add it after a scan has estimated the onset");
        }
        e.onset_s = **onset;
      }
      const SensorTriadModel& triad = term.family->sensor == Sensor::kGyro ? model.gyro : model.acc;
      // The sensor's white noise averaged over one update interval: the size of
      // error the data resolve in one step.
      const double noise = triad.white_noise_density.maxCoeff() / std::sqrt(update_interval_s);
      const double drift = std::max({triad.bias[0].sigma, triad.bias[1].sigma, triad.bias[2].sigma});
      const double scale = diffuse_prior_scale * std::max(noise, drift);
      if (term.family->kind == EffectKind::kFault) {
        // A step on the scale of a turn-on bias; a ramp that reaches it over the run.
        e.prior_sigma[0] = term.family->regressor == Regressor::kRamp ? scale / std::max(run.DurationS(), 1.0) : scale;
        model.effects.push_back(e);
        continue;
      }
      switch (term.family->process) {
        case RandomProcess::kNone: {
          const auto rms = RegressorRms(run, term);
          for (int p = 0; p < term.family->parameters_per_term; ++p) {
            // An effect the run cannot excite keeps a prior on the scale of the drift itself.
            const double r = rms[static_cast<size_t>(p)];
            e.prior_sigma[static_cast<size_t>(p)] = r > 0.0 ? scale / r : scale;
          }
          break;
        }
        case RandomProcess::kRandomWalk:
          // A walk that reaches the drift's σ over the drift's own correlation time.
          e.random_walk_density = drift / std::sqrt(std::max(triad.bias[term.axis].tau_s, update_interval_s));
          break;
        case RandomProcess::kSecondOrderMarkov:
          e.second_order_sigma = triad.bias[term.axis].sigma;
          e.second_order_alpha_per_s = 1.0 / std::max(triad.bias[term.axis].tau_s, update_interval_s);
          e.second_order_beta_rad_s = 2.0 * std::numbers::pi * e.second_order_alpha_per_s;
          break;
      }
      model.effects.push_back(e);
    }
  }
  return absl::OkStatus();
}

namespace {

// One run of a model through the filter, the smoother and the monitor — and,
// when asked, the missing-effect scan.
struct ModelPass {
  ErrorModel model;
  std::unique_ptr<StateLayout> layout;
  ForwardPass forward;
  SmoothedPass smoothed;
  MonitorResult monitor;
  std::unique_ptr<ScoreTestObserver> scan;
  std::vector<OnsetFit> onsets;  // the fault terms' scan, with `scan`
  std::vector<std::string> segment_motion;
  // The innovations' log-likelihood with every added constant effect at its
  // maximum-likelihood value (the profile likelihood), see ProfileCorrection.
  double log_likelihood = 0.0;
};

// Constant effects enter the filter as states with a diffuse prior N(0, Σ);
// the filter's log-likelihood is then the marginal one, lower than the
// likelihood at the parameters' maximum by the prior's weight. With the final
// posterior N(x, P) of the constants and the data's information I = P⁻¹ − Σ⁻¹,
// in Σ-whitened coordinates (Σ = LLᵀ, Ĩ = Lᵀ I L with eigenpairs λ_i, u_i,
// g = Lᵀ P⁻¹ x):
//   ℓ_max − ℓ_marginal = ½ Σ_i [ln(1 + λ_i) + (u_iᵀ g)² / (λ_i (1 + λ_i))]
// over the directions the data inform (Harvey, Forecasting, Structural Time
// Series Models and the Kalman Filter, 1989, §3.4: the diffuse likelihood).
double ProfileCorrection(const ForwardPass& fw, const ErrorModel& model, const StateLayout& layout) {
  std::vector<int> states;
  std::vector<double> prior_sigma;
  for (const SensorState& s : layout.sensor_states()) {
    if (s.dynamics != StateDynamics::kConstant || s.effect < 0) continue;
    states.push_back(s.index);
    prior_sigma.push_back(model.effects[static_cast<size_t>(s.effect)].prior_sigma[static_cast<size_t>(s.parameter)]);
  }
  if (states.empty() || fw.epochs() == 0) return 0.0;
  const auto m = static_cast<Eigen::Index>(states.size());
  Eigen::MatrixXd P_full;
  UnpackSymmetric(fw.P_filt.row(fw.epochs() - 1).data(), fw.state_size, P_full);
  Eigen::MatrixXd P(m, m);
  Eigen::VectorXd x(m), L(m);
  for (Eigen::Index a = 0; a < m; ++a) {
    x[a] = fw.x_filt(fw.epochs() - 1, states[static_cast<size_t>(a)]);
    L[a] = prior_sigma[static_cast<size_t>(a)];
    for (Eigen::Index b = 0; b < m; ++b) P(a, b) = P_full(states[static_cast<size_t>(a)], states[static_cast<size_t>(b)]);
  }
  const Eigen::LDLT<Eigen::MatrixXd> P_ldlt(P);
  // Ĩ = L P⁻¹ L − 1 (Σ diagonal), g = L P⁻¹ x.
  Eigen::MatrixXd I_tilde = L.asDiagonal() * P_ldlt.solve(Eigen::MatrixXd(L.asDiagonal()));
  I_tilde.diagonal().array() -= 1.0;
  const Eigen::VectorXd g = L.asDiagonal() * P_ldlt.solve(x);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (I_tilde + I_tilde.transpose()));
  double correction = 0.0;
  const double top = std::max(eig.eigenvalues().maxCoeff(), 0.0);
  for (Eigen::Index i = 0; i < m; ++i) {
    const double lambda = eig.eigenvalues()[i];
    if (!(lambda > 1e-9 * top) || !(lambda > 0.0)) continue;
    const double gi = eig.eigenvectors().col(i).dot(g);
    correction += 0.5 * (std::log1p(lambda) + gi * gi / (lambda * (1.0 + lambda)));
  }
  return correction;
}

absl::StatusOr<ModelPass> RunPass(const BenchRun& run, const EpochRun& epochs, const ErrorModel& model,
                                  const std::vector<SampleOutlier>& spikes, const AnalysisOptions& options,
                                  bool with_scan) {
  ModelPass pass;
  pass.model = model;
  pass.layout = std::make_unique<StateLayout>(pass.model);
  const int segment_epochs =
      std::max(1, static_cast<int>(std::lround(options.segment_s / options.filter.update_interval_s)));
  if (with_scan) {
    pass.scan = std::make_unique<ScoreTestObserver>(*pass.layout, epochs, AbsentConstantCandidates(pass.model), segment_epochs);
  }
  auto forward = RunForwardFilter(epochs, pass.model, pass.scan.get());
  if (!forward.ok()) return forward.status();
  pass.forward = *std::move(forward);
  auto smoothed = RunSmoother(pass.forward, ident::DriftSmootherOptions(pass.model, *pass.layout, pass.forward,
                                                                        options.correlation));
  if (!smoothed.ok()) return smoothed.status();
  pass.smoothed = *std::move(smoothed);
  pass.monitor = Monitor(pass.forward, pass.smoothed, *pass.layout, spikes, options.monitor);
  pass.log_likelihood = pass.forward.log_likelihood + ProfileCorrection(pass.forward, pass.model, *pass.layout);
  if (with_scan) {
    pass.segment_motion = SegmentMotion(run, pass.forward, segment_epochs);
    pass.onsets = ScanOnsets(pass.forward, *pass.layout, epochs, AbsentFaultTerms(pass.model), options.onset_scan);
  }
  return pass;
}

void FillFit(const ModelPass& pass, const BenchRun& run, const AnalysisOptions& options, AnalysisReport& r) {
  const MonitorResult& m = pass.monitor;
  r.verdict = m.verdict;
  r.model_effects = pass.model.EffectNames();
  r.parameter_count = pass.model.ParameterCount();
  r.channels = m.channels;
  r.nis_mean = m.nis_mean;
  r.nis_band_low = m.nis_band_low;
  r.nis_band_high = m.nis_band_high;
  r.log_likelihood = pass.log_likelihood;
  r.scalar_updates = pass.forward.scalar_updates;
  r.aic = 2.0 * r.parameter_count - 2.0 * r.log_likelihood;
  r.bic = r.parameter_count * std::log(static_cast<double>(std::max(1, r.scalar_updates))) - 2.0 * r.log_likelihood;
  r.gamma2 = m.gamma2;
  r.eta2 = m.eta2;
  r.faults = m.faults;
  r.localisation = m.localisation;
  r.discrepancies = m.discrepancies;
  r.duration_s = run.DurationS();
  r.samples = run.samples.size();
  r.sample_rate_hz = 1.0 / run.NominalIntervalS();
  r.update_interval_s = options.filter.update_interval_s;
}

// The added constant effects' estimates: the final filtered states (constants
// keep their value, so the last epoch's estimate is the smoothed one).
std::vector<ParameterEstimate> ConstantEffectEstimates(const ModelPass& pass) {
  std::vector<ParameterEstimate> out;
  const int K = pass.forward.epochs();
  if (K == 0) return out;
  for (const SensorState& s : pass.layout->sensor_states()) {
    if (s.dynamics != StateDynamics::kConstant || s.effect < 0) continue;
    const ModelEffect& e = pass.model.effects[static_cast<size_t>(s.effect)];
    ParameterEstimate p;
    p.name = s.name;
    p.value = pass.forward.x_filt(K - 1, s.index);
    p.std_error = std::sqrt(pass.smoothed.variance(K - 1, s.index));
    p.method = "FILTER";
    p.unit = std::string(e.term.family->unit);
    out.push_back(p);
  }
  return out;
}

// A random-structure effect proposed by correlation processing or by the
// likelihood's structure tests.
struct StructureProposal {
  ModelEffect effect;
  EffectCandidate candidate;
  // Starting points its screen searched (the fit's profile grid): the
  // Bonferroni factor of its p-value.
  int searched_starts = 1;
  // A walk or pair from the likelihood's tests: its statistic is a
  // likelihood ratio already, and a model that takes it takes its
  // parameters and the drift σ fitted with it, and reports them.
  std::optional<ident::StructureEstimate> fitted;
};

// What a scan's structure tests said of the random structures they did not
// propose, by effect name: each one's statistic below its screen, or why it
// was not tested. The report lists every catalogue effect the model lacks.
using StructureOutcomes = std::map<std::string, EffectCandidate>;

// The drift of a sensor axis in DriftSelection order (gyro x, y, z, then accelerometer).
int DriftIndex(Sensor sensor, int axis) { return (sensor == Sensor::kGyro ? 0 : 3) + axis; }
int DriftIndex(const EffectTerm& term) { return DriftIndex(term.family->sensor, term.axis); }

// A random structure's candidate from `source` ("STRUCTURE", "LIKELIHOOD")
// with nothing measured yet: no statistic, no estimate (p = 1); its degrees
// of freedom are the structure's own parameters.
EffectCandidate StructureCandidate(const EffectTerm& term, const char* source) {
  EffectCandidate c;
  c.name = term.Name();
  c.family = std::string(term.family->name);
  c.unit = std::string(term.family->unit);
  c.source = source;
  c.dof = term.family->process == RandomProcess::kSecondOrderMarkov ? 3 : 1;
  c.std_error = std::numeric_limits<double>::infinity();
  return c;
}

// The catalogue effect a correlation-function family of drift `d` means, with
// its magnitude: a walk (random walk; a second exponential longer than half
// the run, dσ²/dt = 2σ₂²/τ₂), a second-order pair (exponential-cosine).
std::optional<StructureProposal> StructureOfFit(const DriftCorrelation& d, const ident::FamilyFit& f, double run_s) {
  const int drift = DriftIndex(d.sensor, d.axis);
  StructureProposal p;
  std::string effect;
  if (f.family == ident::CorrelationFamily::kRandomWalk) {
    effect = ident::WalkName(drift);
    p.effect.random_walk_density = f.Parameter("density")->value;
    p.candidate.estimate = p.effect.random_walk_density;
    p.candidate.std_error = f.Parameter("density")->std_error;
  } else if (f.family == ident::CorrelationFamily::kExponentialCosine) {
    effect = ident::SecondOrderName(drift);
    p.effect.second_order_sigma = f.Parameter("sigma2")->value;
    p.effect.second_order_alpha_per_s = 1.0 / f.Parameter("tau2_s")->value;
    p.effect.second_order_beta_rad_s = 2.0 * std::numbers::pi / f.Parameter("period_s")->value;
    p.candidate.estimate = p.effect.second_order_sigma;
    p.candidate.std_error = f.Parameter("sigma2")->std_error;
    p.searched_starts = 16;  // the profile grid of period × decay (correlation.cc)
  } else if (f.family == ident::CorrelationFamily::kTwoExponentials && f.Parameter("tau2_s")->value >= 0.5 * run_s) {
    effect = ident::WalkName(drift);
    const double s2 = f.Parameter("sigma2")->value;
    const double t2 = f.Parameter("tau2_s")->value;
    p.effect.random_walk_density = s2 * std::sqrt(2.0 / t2);
    p.candidate.estimate = p.effect.random_walk_density;
    p.candidate.std_error = f.Parameter("sigma2")->std_error * std::sqrt(2.0 / t2);
    p.searched_starts = 6;
  } else {
    return std::nullopt;
  }
  auto terms = ParseEffectSelector(effect);
  if (!terms.ok()) return std::nullopt;
  p.effect.term = terms->front();
  EffectCandidate c = StructureCandidate(p.effect.term, "STRUCTURE");
  c.estimate = p.candidate.estimate;
  c.std_error = p.candidate.std_error;
  c.note = std::string("correlation function of ") + d.state + " is " + ident::CorrelationFamilyName(f.family) +
           ", not exponential";
  p.candidate = std::move(c);
  return p;
}

// Correlation processing's structures on the drifts it resolved: those whose
// family beats the exponential at `screen_alpha` are proposed; the others'
// tests go to `outcomes` (the stronger where two families mean one effect).
std::vector<StructureProposal> ProposeStructures(const std::vector<DriftCorrelation>& drifts, double run_s,
                                                 double screen_alpha, StructureOutcomes& outcomes) {
  std::vector<StructureProposal> out;
  for (const DriftCorrelation& d : drifts) {
    if (!d.analysis.resolved) continue;
    for (const ident::FamilyFit& f : d.analysis.fits) {
      if (!f.converged) continue;
      std::optional<StructureProposal> p = StructureOfFit(d, f, run_s);
      if (!p.has_value()) continue;
      if (f.lr_p_value >= screen_alpha) {
        EffectCandidate c = p->candidate;
        c.statistic = f.lr_statistic;
        c.dof = f.lr_dof;
        c.p_value = f.lr_p_value;
        char buf[192];
        std::snprintf(buf, sizeof buf, "; its fit to the correlation function gains χ² %.1f, p = %.2g (%d starts): "
                      "below the screen", f.lr_statistic, f.lr_p_value, p->searched_starts);
        c.note = "correlation function of " + d.state + " against " + ident::CorrelationFamilyName(f.family) + buf;
        auto [it, inserted] = outcomes.emplace(c.name, c);
        if (!inserted && c.p_value < it->second.p_value) it->second = c;
        continue;
      }
      // The first family that means an effect proposes it.
      if (std::none_of(out.begin(), out.end(),
                       [&](const StructureProposal& o) { return o.effect.term == p->effect.term; })) {
        out.push_back(*std::move(p));
      }
    }
  }
  return out;
}

// Confirms each proposal with the filter's exact likelihood: model A plus the
// effect, against model A.
std::vector<StructureProposal> ConfirmStructures(const BenchRun& run, const EpochRun& epochs, const ModelPass& a,
                                                 std::vector<StructureProposal> proposals,
                                                 const std::vector<SampleOutlier>& spikes,
                                                 const AnalysisOptions& options) {
  const double log_n = std::log(static_cast<double>(std::max(1, a.forward.scalar_updates)));
  for (StructureProposal& p : proposals) {
    ErrorModel b = a.model;
    if (p.fitted.has_value() || b.FindEffect(p.effect.term) >= 0) continue;
    b.effects.push_back(p.effect);
    auto pass = RunPass(run, epochs, b, spikes, options, /*with_scan=*/false);
    EffectCandidate& c = p.candidate;
    if (!pass.ok()) {
      c.identifiable = false;
      c.note += "; could not confirm: " + std::string(pass.status().message());
      continue;
    }
    c.statistic = std::max(0.0, 2.0 * (pass->log_likelihood - a.log_likelihood));
    c.p_value = ident::StructurePValue(c.statistic, c.dof, p.searched_starts);
    c.predicted_delta_aic = -c.statistic + 2.0 * c.dof;
    c.predicted_delta_bic = -c.statistic + c.dof * log_n;
  }
  return proposals;
}

// The drifts correlation processing resolved, in DriftSelection order.
ident::DriftSelection ResolvedDrifts(const std::vector<DriftCorrelation>& drifts) {
  ident::DriftSelection selection{};
  for (int d = 0; d < 6; ++d) {
    const std::string name = ident::DriftName(d);
    selection[static_cast<size_t>(d)] = std::any_of(
        drifts.begin(), drifts.end(), [&](const DriftCorrelation& c) { return c.state == name && c.analysis.resolved; });
  }
  return selection;
}

// A random structure no test measured on this model, and why.
EffectCandidate UntestedStructure(const EffectTerm& term, const std::string& why) {
  EffectCandidate c = StructureCandidate(term, "LIKELIHOOD");
  c.tested = false;
  c.note = "not tested on this model: " + why;
  return c;
}

// Bias random walks and second-order pairs by the innovations' likelihood
// (drift_likelihood.h), on every drift axis the model has none on. Also on a
// run whose monitoring flags faults: a walk that has wandered far trips the
// drift monitor, and the candidate hides nothing — the report keeps the
// fault intervals of its model. As correlation processing's structures, a
// structure is screened, then measured against model A: the screen is the
// nested test (the structure beyond its drift σ re-fitted alone, χ² with its
// own parameters, at `screen_alpha` over the fit's starting points) — a
// wider drift alone is not a structure; the statistic is 2(ℓ̂ − ℓ_A), what
// the structure with its re-fitted drift explains of model A's innovations,
// on its parameters and the drift σ, the scale every other candidate is
// ranked on.
//
// Walks on every axis. Second-order pairs on the axes whose drift
// correlation processing left unresolved — where it resolves the drift, its
// exponential-cosine family tests the pair (ProposeStructures) — and only
// while no constant term is significant: a pair fitted to a model that lacks
// a constant effect soaks up that effect's signal (a drift widened to carry
// a scale factor, in another guise), and each of its passes costs more than
// a base pass (two states an axis). The constant effect is added first; the
// next scan tests the pairs.
std::vector<StructureProposal> LikelihoodStructureProposals(const EpochRun& epochs, const ModelPass& pass,
                                                            const ErrorModel& a_priori,
                                                            const std::vector<DriftCorrelation>& drifts,
                                                            bool constant_significant, double screen_alpha,
                                                            const AnalysisOptions& options,
                                                            StructureOutcomes& outcomes,
                                                            std::vector<std::string>* notes) {
  std::vector<StructureProposal> out;
  ident::DriftSelection every_axis;
  every_axis.fill(true);
  ident::DriftSelection unresolved = ResolvedDrifts(drifts);
  for (bool& axis : unresolved) axis = !axis;
  const double log_n = std::log(static_cast<double>(std::max(1, pass.forward.scalar_updates)));
  struct Test {
    bool enabled;
    const char* what;
    decltype(&ident::IdentifyWalksByLikelihood) fit;
    ident::DriftSelection axes;
    decltype(&ident::WalkName) structure_name;
  };
  const Test tests[] = {
      {options.test_walks_by_likelihood, "bias random walks", &ident::IdentifyWalksByLikelihood, every_axis,
       &ident::WalkName},
      {options.test_second_orders_by_likelihood && !constant_significant, "second-order drifts",
       &ident::IdentifySecondOrdersByLikelihood, unresolved, &ident::SecondOrderName},
  };
  if (options.test_second_orders_by_likelihood && constant_significant) {
    for (int d = 0; d < 6; ++d) {
      if (!unresolved[static_cast<size_t>(d)]) continue;
      auto terms = ParseEffectSelector(ident::SecondOrderName(d));
      if (!terms.ok()) continue;
      outcomes.insert_or_assign(
          terms->front().Name(),
          UntestedStructure(terms->front(), "a constant term is significant, and a pair fitted beside a missing "
                                            "constant effect soaks up its signal: the model with that effect "
                                            "tests it"));
    }
  }
  for (const Test& test : tests) {
    if (!test.enabled) continue;
    auto fitted = test.fit(epochs, pass.model, a_priori, test.axes, screen_alpha, options.drift_likelihood);
    if (!fitted.ok()) {
      if (notes != nullptr) {
        notes->push_back(std::string("no likelihood test of ") + test.what + ": " +
                         std::string(fitted.status().message()));
      }
      continue;
    }
    // The axes the screen tried: a structure its first EM step shrank (not
    // among `structures`) is one this run does not tell from the axis' drift.
    for (int d = 0; d < 6; ++d) {
      const std::string name = test.structure_name(d);
      auto terms = ParseEffectSelector(name);
      if (!fitted->screened[static_cast<size_t>(d)] || !terms.ok()) continue;
      EffectCandidate c = StructureCandidate(terms->front(), "LIKELIHOOD");
      c.note = std::string("likelihood of the innovations: the first EM step from the structure hypothesis "
                           "shrank it — this run does not tell it from a wider ") + ident::DriftName(d) + " drift";
      outcomes.insert_or_assign(name, c);
    }
    for (const ident::StructureEstimate& w : fitted->structures) {
      auto terms = ParseEffectSelector(w.effect);
      if (!terms.ok()) continue;
      if (!(ident::NestedPValue(w) < screen_alpha)) {
        EffectCandidate c = StructureCandidate(terms->front(), "LIKELIHOOD");
        c.estimate = w.parameters.front().value;
        c.statistic = w.statistic;
        c.p_value = ident::NestedPValue(w);
        char buf[256];
        std::snprintf(buf, sizeof buf, "likelihood of the innovations: 2Δℓ = %.1f beyond the drift σ re-fitted "
                      "alone, p = %.2g (%d starts) — below the screen; no standard error computed",
                      w.statistic, c.p_value, w.starts);
        c.note = buf;
        outcomes.insert_or_assign(w.effect, c);
        continue;
      }
      StructureProposal p;
      p.effect = w.fitted;
      p.fitted = w;
      p.candidate = StructureCandidate(p.effect.term, "LIKELIHOOD");
      EffectCandidate& c = p.candidate;
      c.estimate = w.parameters.front().value;
      c.std_error = w.parameters.front().std_error;
      c.dof = w.dof + 1;
      // With several structures kept, the joint gain less the others' own.
      double others = 0.0;
      for (const ident::StructureEstimate& o : fitted->structures) others += o.drift == w.drift ? 0.0 : o.statistic;
      c.statistic = std::max(w.statistic, 2.0 * (fitted->log_likelihood_after - pass.log_likelihood) - others);
      // χ² for a parameter on its boundary is conservative (drift_likelihood.h).
      c.p_value = ident::StructurePValue(c.statistic, c.dof, w.starts);
      c.predicted_delta_aic = -c.statistic + 2.0 * c.dof;
      c.predicted_delta_bic = -c.statistic + c.dof * log_n;
      std::string parameters;
      for (const ParameterEstimate& e : w.parameters) {
        char buf[96];
        std::snprintf(buf, sizeof buf, "%s%s %.3g %s", parameters.empty() ? "" : ", ",
                      e.name.substr(e.name.rfind('.') + 1).c_str(), e.value, e.unit.c_str());
        parameters += buf;
      }
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.3g %s", w.drift_sigma.value, w.drift_sigma.unit.c_str());
      char nested[96];
      std::snprintf(nested, sizeof nested, "2Δℓ = %.1f beyond the drift σ re-fitted alone", w.statistic);
      c.note = "likelihood of the innovations with " + parameters + " and the drift σ re-fitted (" +
               ident::DriftName(w.drift) + ".sigma " + buf + " with it); " + nested;
      out.push_back(std::move(p));
    }
  }
  return out;
}

// Terms and structures ranked together, Holm over all that were tested:
// the structures proposed, and the others with what their tests said. The
// candidates significant at family-wise `alpha` come first, the most probable
// explanation first: lowest predicted ΔBIC, the order in which the analysis
// adds them (Schwarz, Ann. Stat. 6(2), 1978). Beyond significance a p-value
// no longer ranks explanations: a step and a ramp on one axis carry the same
// evidence, but the bound on the maximum over onsets penalises them unequally.
// The rest follow by Holm-adjusted p-value.
std::vector<EffectCandidate> MergeCandidates(std::vector<EffectCandidate> terms,
                                             const std::vector<StructureProposal>& structures,
                                             std::vector<EffectCandidate> other_structures, double alpha) {
  for (const StructureProposal& s : structures) terms.push_back(s.candidate);
  for (EffectCandidate& c : other_structures) terms.push_back(std::move(c));
  std::vector<size_t> tested;
  std::vector<double> p;
  for (size_t i = 0; i < terms.size(); ++i) {
    if (!terms[i].identifiable || !terms[i].tested) continue;
    tested.push_back(i);
    p.push_back(terms[i].p_value);
  }
  std::vector<double> adjusted(p.size());
  stats::HolmAdjust(p, adjusted);
  for (size_t j = 0; j < tested.size(); ++j) terms[tested[j]].p_value_holm = adjusted[j];
  std::stable_sort(terms.begin(), terms.end(), [alpha](const EffectCandidate& a, const EffectCandidate& b) {
    if (a.identifiable != b.identifiable) return a.identifiable;
    if (a.SignificantAt(alpha) != b.SignificantAt(alpha)) return a.SignificantAt(alpha);
    if (a.SignificantAt(alpha) && a.predicted_delta_bic != b.predicted_delta_bic) {
      return a.predicted_delta_bic < b.predicted_delta_bic;
    }
    if (a.p_value_holm != b.p_value_holm) return a.p_value_holm < b.p_value_holm;
    return a.statistic > b.statistic;
  });
  return terms;
}

// Everything a report says about model A's pass: fit, identification, candidates.
struct Findings {
  std::vector<EffectCandidate> candidates;
  std::vector<EffectCandidate> families;
  std::vector<StructureProposal> structures;
  std::vector<DriftCorrelation> drifts;
};

// A model's pass scanned for missing effects, what the scan found and the
// notes it wrote.
struct ScannedModel {
  ModelPass pass;
  Findings found;
  std::vector<std::string> notes;
};

// `drifts`: correlation processing of this pass's smoothed drifts.
Findings FindMissingEffects(const BenchRun& run, const EpochRun& epochs, const ModelPass& pass, std::vector<DriftCorrelation> drifts,
                            const ErrorModel& a_priori, const std::vector<SampleOutlier>& spikes,
                            const AnalysisOptions& options, std::vector<std::string>* notes) {
  Findings f;
  f.drifts = std::move(drifts);
  RankedEffects ranked = RankMissingEffects(*pass.scan, pass.forward, run, pass.segment_motion, options.finder);
  f.families = std::move(ranked.families);
  // Screening level of a structure before the likelihood confirms it: the
  // family-wise α over the drifts and the structural families tried.
  const double screen_alpha = options.finder.family_wise_alpha / (6.0 * 3.0);
  // The likelihood's structures first: where correlation processing proposes
  // the same structure, the likelihood's estimate is kept.
  const bool constant_significant =
      std::any_of(ranked.terms.begin(), ranked.terms.end(), [&](const EffectCandidate& c) {
        return c.SignificantAt(options.finder.family_wise_alpha);
      });
  StructureOutcomes likelihood_outcomes, correlation_outcomes;
  std::vector<StructureProposal> proposals = LikelihoodStructureProposals(
      epochs, pass, a_priori, f.drifts, constant_significant, screen_alpha, options, likelihood_outcomes, notes);
  for (StructureProposal& p : ProposeStructures(f.drifts, run.DurationS(), screen_alpha, correlation_outcomes)) {
    if (std::none_of(proposals.begin(), proposals.end(),
                     [&](const StructureProposal& o) { return o.effect.term == p.effect.term; })) {
      proposals.push_back(std::move(p));
    }
  }
  // Structures already in the model are not candidates.
  proposals.erase(std::remove_if(proposals.begin(), proposals.end(),
                                 [&](const StructureProposal& p) { return pass.model.FindEffect(p.effect.term) >= 0; }),
                  proposals.end());
  // Every other random structure of the catalogue the model lacks, with what
  // its test said (the likelihood's where it ran), or why none ran.
  std::vector<EffectCandidate> others;
  for (const EffectTerm& term : AllCatalogueTerms()) {
    if (term.family->kind != EffectKind::kRandom || pass.model.FindEffect(term) >= 0 ||
        std::any_of(proposals.begin(), proposals.end(), [&](const StructureProposal& p) { return p.effect.term == term; })) {
      continue;
    }
    const std::string name = term.Name();
    if (auto it = likelihood_outcomes.find(name); it != likelihood_outcomes.end()) {
      others.push_back(it->second);
    } else if (auto jt = correlation_outcomes.find(name); jt != correlation_outcomes.end()) {
      others.push_back(jt->second);
    } else {
      others.push_back(UntestedStructure(
          term, ident::DriftOf(pass.model, DriftIndex(term)).sigma > 0.0
                    ? "neither the likelihood's test (off, or failed: see the notes) nor correlation processing's "
                      "(the " + ident::DriftName(DriftIndex(term)) + " drift unresolved, or its fit not converged) "
                      "measured it"
                    : "the model has no " + ident::DriftName(DriftIndex(term)) + " drift to test it beside"));
    }
  }
  f.structures = ConfirmStructures(run, epochs, pass, std::move(proposals), spikes, options);
  for (EffectCandidate& c : FaultCandidates(pass.onsets, pass.forward.scalar_updates)) others.push_back(std::move(c));
  f.candidates = MergeCandidates(std::move(ranked.terms), f.structures, std::move(others),
                                 options.finder.family_wise_alpha);
  return f;
}

Findings FindMissingEffects(const BenchRun& run, const EpochRun& epochs, const ModelPass& pass, const ErrorModel& a_priori,
                            const std::vector<SampleOutlier>& spikes, const AnalysisOptions& options,
                            std::vector<std::string>* notes) {
  return FindMissingEffects(run, epochs, pass,
                            ident::CorrelateDrifts(pass.forward, pass.smoothed, *pass.layout, options.correlation, notes),
                            a_priori, spikes, options, notes);
}

// The significant, identifiable candidate whose predicted ΔBIC is lowest,
// among single terms and whole families; nullptr when none is significant.
// A term and its family often score alike when one axis carries the effect;
// the family's extra parameters then cost more than they explain. When every
// axis carries it, the family explains far more than any term, and it is not
// mistaken for a look-alike term of another family (a common scale factor
// for two misalignments, say). Schwarz, Ann. Stat. 6(2), 1978.
const EffectCandidate* LowestBicSignificant(const std::vector<EffectCandidate>& terms,
                                            const std::vector<EffectCandidate>& families,
                                            const AnalysisOptions& options) {
  const EffectCandidate* best = nullptr;
  for (const auto* list : {&terms, &families}) {
    for (const EffectCandidate& c : *list) {
      if (!c.SignificantAt(options.finder.family_wise_alpha)) continue;
      if (best == nullptr || c.predicted_delta_bic < best->predicted_delta_bic) best = &c;
    }
  }
  return best;
}

// The effect `--discover` adds next.
const EffectCandidate* NextDiscovery(const Findings& found, const AnalysisOptions& options) {
  return LowestBicSignificant(found.candidates, found.families, options);
}

// The identified parameters of a model that took structures of `found`:
// what the likelihood identified with each (a walk's K or a pair's σ₂, τ₂
// and period, and the drift σ fitted with it)
// replaces the earlier estimate of the same name.
std::vector<ParameterEstimate> WithTakenStructures(std::vector<ParameterEstimate> identified,
                                                   const ErrorModel& model, const Findings& found) {
  for (const StructureProposal& p : found.structures) {
    if (!p.fitted.has_value() || model.FindEffect(p.effect.term) < 0) continue;
    std::vector<ParameterEstimate> taken = p.fitted->parameters;
    taken.push_back(p.fitted->drift_sigma);
    for (const ParameterEstimate& e : taken) {
      std::erase_if(identified, [&](const ParameterEstimate& q) { return q.name == e.name; });
      identified.push_back(e);
    }
  }
  return identified;
}

// Model `base` plus `selectors`, with priors from what model A's scan and
// correlation processing found; anything not found gets the diffuse prior.
absl::StatusOr<ErrorModel> ExtendModel(const BenchRun& run, const ErrorModel& base,
                                       const std::vector<std::string>& selectors, const ModelPass& a,
                                       const Findings& found, const AnalysisOptions& options) {
  ErrorModel model = base;
  std::vector<std::string> fallback;
  for (const std::string& selector : selectors) {
    auto terms = ParseEffectSelector(selector);
    if (!terms.ok()) return terms.status();
    auto onset = ParseOnset(selector);
    if (!onset.ok()) return onset.status();
    for (const EffectTerm& term : *terms) {
      if (model.FindEffect(term) >= 0) continue;
      if (term.family->kind == EffectKind::kFault) {
        // At the onset named, else at the scan's: prior wide against the scan's estimate.
        const auto c = std::find_if(found.candidates.begin(), found.candidates.end(), [&](const EffectCandidate& x) {
          return x.name == term.Name() && x.onset_s.has_value();
        });
        const std::optional<double> onset_s = onset->has_value() ? *onset
                                              : c != found.candidates.end() ? c->onset_s
                                                                            : std::nullopt;
        if (c == found.candidates.end() || !onset_s.has_value()) {
          fallback.push_back(onset_s.has_value() ? term.Name() + "@" + std::to_string(*onset_s) : term.Name());
          continue;
        }
        ModelEffect e;
        e.term = term;
        e.onset_s = *onset_s;
        e.prior_sigma[0] = options.estimated_prior_scale * std::max(std::abs(c->estimate), 3.0 * c->std_error);
        model.effects.push_back(e);
        continue;
      }
      auto structure = std::find_if(found.structures.begin(), found.structures.end(),
                                    [&](const StructureProposal& p) { return p.effect.term == term; });
      if (structure != found.structures.end()) {
        model.effects.push_back(structure->effect);
        if (structure->fitted.has_value()) {
          ident::DriftOf(model, structure->fitted->drift).sigma = structure->fitted->drift_sigma.value;
        }
        continue;
      }
      // A constant the scan estimated: prior wide against its estimate.
      bool placed = false;
      if (term.family->kind == EffectKind::kConstant && a.scan != nullptr) {
        ModelEffect e;
        e.term = term;
        const auto& cols = a.scan->columns();
        const Eigen::MatrixXd& I = a.scan->information();
        const Eigen::VectorXd& s = a.scan->score();
        placed = true;
        for (int p = 0; p < term.family->parameters_per_term; ++p) {
          auto it = std::find_if(cols.begin(), cols.end(),
                                 [&](const CandidateColumn& c) { return c.term == term && c.parameter == p; });
          const auto i = static_cast<Eigen::Index>(it - cols.begin());
          if (it == cols.end() || !(I(i, i) > 0.0)) {
            placed = false;
            break;
          }
          const double beta = s[i] / I(i, i);
          const double se = 1.0 / std::sqrt(I(i, i));
          e.prior_sigma[static_cast<size_t>(p)] = options.estimated_prior_scale * std::max(std::abs(beta), 3.0 * se);
        }
        if (placed) model.effects.push_back(e);
      }
      if (!placed) fallback.push_back(term.Name());
    }
  }
  if (auto st = AddEffects(run, fallback, options.filter.update_interval_s, options.diffuse_prior_scale, model); !st.ok()) {
    return st;
  }
  return model;
}

ModelComparison Compare(const ModelPass& a, const ModelPass& b, const AnalysisReport& ra, const AnalysisReport& rb,
                        double predicted_lr) {
  ModelComparison c;
  c.baseline_effects = a.model.EffectNames();
  for (const std::string& e : b.model.EffectNames()) {
    if (std::find(c.baseline_effects.begin(), c.baseline_effects.end(), e) == c.baseline_effects.end()) {
      c.added_effects.push_back(e);
    }
  }
  for (size_t i = 0; i < ra.channels.size() && i < rb.channels.size(); ++i) {
    c.channels.push_back({ra.channels[i].name, ra.channels[i], rb.channels[i]});
  }
  c.nis_mean_before = ra.nis_mean;
  c.nis_mean_after = rb.nis_mean;
  c.log_likelihood_before = ra.log_likelihood;
  c.log_likelihood_after = rb.log_likelihood;
  c.aic_before = ra.aic;
  c.aic_after = rb.aic;
  c.bic_before = ra.bic;
  c.bic_after = rb.bic;
  c.realized_lr = 2.0 * (rb.log_likelihood - ra.log_likelihood);
  c.predicted_lr = predicted_lr;
  return c;
}

// Model A's score statistic for adding `added` jointly (the likelihood ratio it predicts).
// Whether `term_name` is one of the terms `selector` (a term or a family) stands for.
bool SelectorCovers(const std::string& selector, const std::string& term_name) {
  const auto terms = ParseEffectSelector(selector);
  return terms.ok() &&
         std::any_of(terms->begin(), terms->end(), [&](const EffectTerm& t) { return t.Name() == term_name; });
}

double PredictedLikelihoodRatio(const ModelPass& a, const std::vector<std::string>& added, const Findings& found) {
  if (a.scan == nullptr) return 0.0;
  std::vector<Eigen::Index> idx;
  double structure_lr = 0.0;
  for (const std::string& name : added) {
    // A family stands for its terms.
    for (size_t i = 0; i < a.scan->columns().size(); ++i) {
      if (SelectorCovers(name, a.scan->columns()[i].term.Name())) idx.push_back(static_cast<Eigen::Index>(i));
    }
    for (const StructureProposal& p : found.structures) {
      if (p.candidate.name == name) structure_lr += p.candidate.statistic;
    }
    // A fault: the onset scan's likelihood ratio at its onset.
    for (const EffectCandidate& c : found.candidates) {
      if (c.source == "GLR" && c.name == name.substr(0, name.find('@'))) structure_lr += c.statistic;
    }
  }
  if (idx.empty()) return structure_lr;
  const auto n = static_cast<Eigen::Index>(idx.size());
  Eigen::VectorXd s(n);
  Eigen::MatrixXd I(n, n);
  for (Eigen::Index r = 0; r < n; ++r) {
    s[r] = a.scan->score()[idx[static_cast<size_t>(r)]];
    for (Eigen::Index c = 0; c < n; ++c) I(r, c) = a.scan->information()(idx[static_cast<size_t>(r)], idx[static_cast<size_t>(c)]);
  }
  return s.dot(I.completeOrthogonalDecomposition().solve(s)) + structure_lr;
}

void FillSeries(const ModelPass& pass, AnalysisSeries& series) {
  const ForwardPass& fw = pass.forward;
  const SmoothedPass& sm = pass.smoothed;
  series.time_s = fw.epoch_time_s;
  series.measured = fw.z;
  series.residual = fw.innovation;
  series.predicted = fw.z - fw.innovation;
  series.sigma = fw.innovation_variance.cwiseSqrt();
  series.window_ratio = pass.monitor.window_ratio;
  const int m = pass.layout->sensor_count();
  const int b = pass.layout->sensor_begin();
  series.state_names.clear();
  for (const SensorState& s : pass.layout->sensor_states()) series.state_names.push_back(s.name);
  series.forward = fw.x_filt.middleCols(b, m);
  series.smoothed = sm.x.middleCols(b, m);
  series.smoothed_sigma = sm.variance.middleCols(b, m).cwiseSqrt();
  series.backward = sm.backward_x.middleCols(b, m);
  series.discrepancy = sm.discrepancy.middleCols(b, m);
}

// The faults a pass shows: significant fault candidates of its scan, and the
// fault effects of its model whose estimates differ from zero.
std::vector<FaultFinding> FaultFindings(const ModelPass& pass, const Findings& found, const AnalysisOptions& options) {
  const double alpha = options.finder.family_wise_alpha;
  std::vector<FaultFinding> findings = SignificantFaults(found.candidates, alpha);
  const int K = pass.forward.epochs();
  if (K == 0) return findings;
  for (const SensorState& s : pass.layout->sensor_states()) {
    if (s.effect < 0) continue;
    const ModelEffect& e = pass.model.effects[static_cast<size_t>(s.effect)];
    if (e.term.family->kind != EffectKind::kFault) continue;
    const auto f = FaultInModel(e.term, e.onset_s, pass.forward.x_filt(K - 1, s.index),
                                std::sqrt(pass.smoothed.variance(K - 1, s.index)), alpha);
    if (f.has_value()) findings.push_back(*f);
  }
  return findings;
}

// The report of one scanned pass.
AnalysisReport ReportOf(const ModelPass& pass, const Findings& found, const BenchRun& run,
                        const AnalysisOptions& options, const std::vector<ParameterEstimate>& identified,
                        const std::vector<std::string>& notes) {
  AnalysisReport r;
  FillFit(pass, run, options, r);
  ReportFaults(FaultFindings(pass, found, options), run.samples.back().t_s, r);
  r.effect_candidates = found.candidates;
  r.family_candidates = found.families;
  r.correlation = found.drifts;
  r.identified = identified;
  for (const ParameterEstimate& e : ConstantEffectEstimates(pass)) r.identified.push_back(e);
  r.notes = notes;
  return r;
}

// The drift estimates' SEs made consistent with their likelihood ratio
// against `reference` (ident::WidenErrorsToTheLikelihoodRatio), with a note
// naming the drifts widened.
void WidenErrorsOrSay(const EpochRun& epochs, const ErrorModel& reference, ident::DriftLikelihoodResult& ml,
                      std::vector<std::string>& notes) {
  auto widened = ident::WidenErrorsToTheLikelihoodRatio(epochs, reference, ml);
  if (!widened.ok()) {
    notes.push_back("the drift estimates' standard errors were not checked against their likelihood ratio: " +
                    std::string(widened.status().message()));
    return;
  }
  if (widened->empty()) return;
  std::string names;
  for (const std::string& n : *widened) names += (names.empty() ? "" : ", ") + n;
  notes.push_back("standard errors widened to the likelihood ratio against the a-priori values (the curvature at "
                  "the estimate understated how flat the likelihood stays along the σ–τ ridge): " + names);
}

// The likelihood-ratio statistic of the drift estimates against the model's
// values (one degree of freedom per identified parameter, σ or τ).
double DriftStatistic(const ident::DriftLikelihoodResult& ml) {
  return 2.0 * (ml.log_likelihood_after - ml.log_likelihood_before);
}

// The likelihood's drift estimates (drift_likelihood.h) are reported; the
// model takes them when they raise the innovations' log-likelihood beyond
// the likelihood-ratio test of the model's values, χ²(m) at α for m
// identified parameters
// (Wilks, Ann. Math. Statist. 9(1), 1938) — as the correlation retargeting
// keeps a model the data do not contradict. True when the model took them.
// A model whose values are placeholders (an Allan-fit a-priori model: its τ
// a bound of the static segments) has nothing the data must overturn: it
// takes the estimates whatever the statistic.
bool ApplyDriftLikelihood(const ident::DriftLikelihoodResult& ml, double alpha, bool placeholders, ErrorModel& base,
                          std::vector<ParameterEstimate>& identified, std::vector<std::string>& notes) {
  if (!ml.not_identifiable.empty()) {
    std::string names;
    for (const std::string& n : ml.not_identifiable) names += (names.empty() ? "" : ", ") + n;
    notes.push_back("not identifiable with this run's motion (the innovations' likelihood is flat in them): " +
                    names);
  }
  if (ml.identified.empty()) return false;
  for (const ParameterEstimate& p : ml.identified) {
    std::erase_if(identified, [&](const ParameterEstimate& q) { return q.name == p.name; });
    identified.push_back(p);
  }
  const double statistic = DriftStatistic(ml);
  const auto dof = static_cast<int>(ml.identified.size());
  const bool rejects = statistic > stats::ChiSquareQuantile(1.0 - alpha, dof);
  const bool takes = rejects || placeholders;
  if (takes) base = ml.model;
  std::string names;
  for (const ParameterEstimate& p : ml.identified) names += (names.empty() ? "" : ", ") + p.name;
  char buf[200];
  std::snprintf(buf, sizeof buf, " (EM, %d iterations%s, %d filter passes): 2Δℓ = %.1f against χ²(%d) at %.2g — ",
                ml.iterations, ml.converged ? "" : ", not converged", ml.filter_passes, statistic, dof, alpha);
  notes.push_back("drift parameters identified by likelihood of the innovations: " +
                  names + buf +
                  (rejects        ? "the model takes the estimates"
                   : placeholders ? "the model's values were the Allan fit's placeholders: it takes the estimates"
                                  : "the data do not reject the model's values, kept"));
  return takes;
}

}  // namespace

absl::StatusOr<Analysis> Analyze(const BenchRun& input, const AnalysisRequest& request,
                                 const AnalysisOptions& options) {
  if (auto st = options.Validate(); !st.ok()) return st;
  if (input.samples.size() < 2) return absl::InvalidArgumentError("the run has fewer than two samples");
  Progress(options, 0.0, "screening samples");
  BenchRun run = input;
  const std::vector<SampleOutlier> spikes = ScreenAndRepairSpikes(run, options.screening);
  std::vector<std::string> notes;

  Progress(options, 0.05, "Allan deviation");
  std::optional<ident::AllanResult> allan;
  if (options.identify) {
    auto a = ident::AllanAnalysis(run, options.allan);
    if (a.ok()) {
      allan = *std::move(a);
    } else {
      notes.push_back("no Allan analysis: " + std::string(a.status().message()));
    }
  }

  // The a-priori model: datasheet, nominal, else the Allan fit.
  auto a_priori = APrioriModel(run, request.nominal, options.reference);
  bool a_priori_from_allan = false;
  if (!a_priori.ok()) {
    if (!allan.has_value()) return a_priori.status();
    auto from_allan = ident::ErrorModelFromAllan(*allan, options.reference, &notes);
    if (!from_allan.ok()) return from_allan.status();
    a_priori = *std::move(from_allan);
    a_priori_from_allan = true;
    notes.push_back("the run has no complete datasheet and no nominal model: the a-priori model comes from its "
                    "Allan deviation");
  }
  ErrorModel base = *a_priori;
  // Where drift identification starts: the grid searches decades from the
  // a-priori drifts, for a type's nominal model or an Allan fit — a class
  // prior a unit may be far from. A datasheet's drifts are the unit's own
  // specification; a unit far from it shows as a re-tuned drift or as
  // effects near it.
  ident::DriftStartOptions drift_starts = options.drift_starts;
  if (const Datasheet& d = run.metadata.datasheet; d.gyro_bias_sigma_rad_s && d.gyro_bias_tau_s &&
                                                   d.acc_bias_sigma_mps2 && d.acc_bias_tau_s) {
    drift_starts.grid_tau_points = 0;
  }
  const std::vector<ParameterEstimate> removed_constants =
      options.remove_dominant_constants ? RemoveDominantConstants(run, allan, *a_priori, options, notes)
                                        : std::vector<ParameterEstimate>{};
  if (auto st = AddEffects(run, request.baseline_effects, options.filter.update_interval_s,
                           options.diffuse_prior_scale, base);
      !st.ok()) {
    return st;
  }

  // The run condensed to its update epochs once: every pass below filters the epochs.
  auto condensed = CondenseRun(run, base, options.filter.update_interval_s);
  if (!condensed.ok()) return condensed.status();
  const EpochRun& epochs = *condensed;

  // Retargeting: identify, re-tune, until the parameters settle.
  std::vector<ParameterEstimate> identified;
  // The a-priori model's scan: the report's when its missing effects go
  // before any re-tune (`deferred`), or when the re-tunes leave its model.
  std::optional<ScannedModel> scanned;
  bool deferred = false;
  if (options.identify) {
    if (allan.has_value()) {
      identified = ident::ApplyAllanNoise(*allan, *a_priori, base, options.monitor.family_wise_alpha);
      for (const ParameterEstimate& p : ident::AllanParameterEstimates(*allan, &*a_priori)) {
        // The drifts' σ and τ are identified by correlation processing of the
        // whole run; the Allan Markov term of the static segments only seeds
        // an a-priori model.
        const bool drift = p.name.find("_bias_gm.") != std::string::npos;
        if (!drift && std::none_of(identified.begin(), identified.end(),
                                   [&](const ParameterEstimate& q) { return q.name == p.name; })) {
          identified.push_back(p);
        }
      }
    }
    // Terms the Allan fit left at bounds: nothing else re-tunes them (the
    // ACF retargeting needs a resolved drift, the Allan fit a resolved
    // density), and a bound over-predicts the innovations. Their common
    // scale per group by maximum likelihood (retarget.h).
    const ident::UnresolvedNoise unresolved =
        a_priori_from_allan && allan.has_value() ? ident::UnresolvedAllanTerms(*allan) : ident::UnresolvedNoise{};
    if (options.retune_unresolved_noise && unresolved.Any()) {
      Progress(options, 0.08, "maximum-likelihood noise scale");
      auto scaled = ident::ScaleUnresolvedNoise(epochs, base, unresolved, options.noise_scale);
      if (!scaled.ok()) {
        notes.push_back("the noise terms set from Allan bounds were not re-tuned: " +
                        std::string(scaled.status().message()));
      } else {
        base = scaled->model;
        for (const ident::NoiseScaleGroup& g : scaled->groups) {
          std::string terms;
          for (const std::string& t : g.terms) terms += (terms.empty() ? "" : ", ") + t;
          char buf[160];
          std::snprintf(buf, sizeof buf, "× %.3g (SE of ln: %.2g)%s", g.scale, g.log_std_error,
                        g.at_limit ? ", at the search range's limit" : "");
          const bool seeded = g.name.ends_with("seed");
          notes.push_back("re-tuned by maximum likelihood of the innovations, " + g.name + " (" + terms +
                          (seeded ? ", seeded by the Allan fit, not resolved by correlation processing): "
                                  : ", set from Allan bounds): ") +
                          std::string(buf));
        }
        char buf[96];
        std::snprintf(buf, sizeof buf, "%.1f after %d filter passes", scaled->log_likelihood_after -
                      scaled->log_likelihood_before, scaled->filter_passes);
        notes.push_back("the innovations' log-likelihood rose by " + std::string(buf));
        for (const ParameterEstimate& p : scaled->identified) {
          std::erase_if(identified, [&](const ParameterEstimate& q) { return q.name == p.name; });
          identified.push_back(p);
        }
      }
    }
    std::vector<DriftCorrelation> drifts;
    bool faults_flagged = false;  // by the latest pass's monitoring
    bool drifts_by_likelihood = false;  // the deferral's competition took them
    // The drifts by the innovations' likelihood (drift_likelihood.h), from
    // `model`, one of two sets at a time. The drifts correlation processing
    // left unresolved: their σ (τ held at the model's value, which the run
    // does not tell — unless it is an Allan-fit placeholder, a bound or a
    // guess from static segments shorter than the drift's τ). The drifts it
    // resolved: σ and τ, from its estimates (which the retargeted model
    // holds where the data rejected the a-priori values), a start near the
    // likelihood's ridge. Apart, because one EM over both sets crawls: on an
    // eight-hour run with a tripled gyro σ it had not converged after 30
    // steps, that σ still 15 % short.
    auto identify_drifts = [&](const ErrorModel& model, bool resolved_set) {
      Progress(options, 0.6, "maximum-likelihood drift identification");
      const ident::DriftSelection resolved = ResolvedDrifts(drifts);
      ident::DriftSelection selection{}, tau_too{};
      for (size_t d = 0; d < selection.size(); ++d) {
        // A run whose monitoring flags faults (a drift that jumped, say) is
        // not re-tuned: a wider drift would hide the fault the diagnosis is for.
        selection[d] = !faults_flagged && resolved[d] == resolved_set;
        tau_too[d] = selection[d] && (resolved_set || a_priori_from_allan);
      }
      if (drift_starts.grid_tau_points > 0) {
        return ident::IdentifyDriftsFromGrid(epochs, model, *a_priori, selection, tau_too, drift_starts,
                                             options.drift_likelihood);
      }
      return ident::IdentifyDriftsByLikelihood(epochs, model, *a_priori, selection, tau_too,
                                               options.drift_likelihood);
    };
    for (int it = 0; it < options.max_retarget_iterations; ++it) {
      Progress(options, 0.1 + 0.5 * it / options.max_retarget_iterations, "retargeting");
      // The first pass also scans for missing effects: parameters identified
      // under a model whose structure is wrong soak up the missing effect (a
      // drift widened to carry a scale-factor error), so the retargeting waits
      // until the structure is complete.
      const bool first = it == 0;
      auto pass = RunPass(run, epochs, base, spikes, options, /*with_scan=*/first);
      if (!pass.ok()) return pass.status();
      // An a-priori model from the Allan fit is not a specification to
      // protect: its drift τ is a bound of the static segments (the longest τ
      // analysed) or a guess from them, and its misfit shows as effects. Its
      // drifts are re-tuned by the whole run before the scan.
      const bool may_defer = first && !a_priori_from_allan;
      std::vector<std::string> found_notes;
      drifts = ident::CorrelateDrifts(pass->forward, pass->smoothed, *pass->layout, options.correlation,
                                      may_defer ? &found_notes : nullptr);
      // A bias step or ramp the onset scan finds counts too (Bonferroni over its terms).
      faults_flagged = !pass->monitor.faults.empty() ||
                       std::any_of(pass->onsets.begin(), pass->onsets.end(), [&](const OnsetFit& f) {
                         return f.p_value * static_cast<double>(pass->onsets.size()) < options.finder.family_wise_alpha;
                       });
      // The a-priori model's missing effects, the likelihood's structures
      // among them: a walk is a missing effect as much as a constant term,
      // and a drift σ re-tuned before it is tested takes the walk's slow
      // variance (a wider or slower drift over the run), which the walk's
      // nested test then cannot tell from it.
      Findings found;
      const EffectCandidate* best = nullptr;
      if (may_defer) {
        found = FindMissingEffects(run, epochs, *pass, drifts, *a_priori, spikes, options, &found_notes);
        best = LowestBicSignificant(found.candidates, found.families, options);
      }
      if (best != nullptr) {
        // The converse soaking holds too: a drift whose σ is far larger than
        // the model's shows as effects that follow the table's motion (a
        // g-sensitivity, say). The two explanations compete by BIC (Schwarz,
        // Ann. Stat. 6(2), 1978): the drifts' σ by likelihood against the
        // best candidate's predicted ΔBIC.
        if (options.identify_drifts_by_likelihood) {
          // Every drift's σ and τ, from the a-priori values and from starts
          // a decade either side: a unit far from its type's nominal model
          // is the case this competition is for. Also when faults are
          // flagged: a drift far wider than the model's trips the monitor
          // and the onset scan as a jump would, and BIC decides which it is.
          ident::DriftSelection every_drift{};
          every_drift.fill(true);
          const double log_n = std::log(static_cast<double>(std::max(1, pass->forward.scalar_updates)));
          auto ml = ident::IdentifyDriftsFromStarts(epochs, base, *a_priori, every_drift, drift_starts,
                                                    options.drift_likelihood);
          if (ml.ok()) ml = ident::KeepDriftsWorthTheirParameters(epochs, base, *std::move(ml), log_n);
          if (ml.ok()) WidenErrorsOrSay(epochs, *a_priori, *ml, notes);
          if (ml.ok() && !ml->identified.empty()) {
            const double drift_bic = -DriftStatistic(*ml) + static_cast<double>(ml->identified.size()) * log_n;
            if (drift_bic < best->predicted_delta_bic &&
                ApplyDriftLikelihood(*ml, options.monitor.family_wise_alpha, a_priori_from_allan, base, identified, notes)) {
              char buf[160];
              std::snprintf(buf, sizeof buf, "ΔBIC %.1f against the best candidate's %.1f", drift_bic,
                            best->predicted_delta_bic);
              notes.push_back("the a-priori model's misfit is the drifts' σ rather than a missing effect (" +
                              std::string(buf) + "): the model takes them and is scanned again");
              drifts_by_likelihood = true;
              continue;
            }
            // The drifts stay as the a-priori model has them, but what the
            // likelihood measured of them is reported: a drift far from its
            // nominal is evidence for the diagnosis whichever explanation wins.
            for (const ParameterEstimate& p : ml->identified) {
              std::erase_if(identified, [&](const ParameterEstimate& q) { return q.name == p.name; });
              identified.push_back(p);
            }
            char buf[240];
            std::snprintf(buf, sizeof buf, "the drifts' σ and τ by likelihood (%zu parameters worth their cost) reach "
                          "ΔBIC %.1f against the best candidate's %.1f: the candidates stand, and the drift estimates "
                          "are reported beside the a-priori model's values", ml->identified.size(), drift_bic,
                          best->predicted_delta_bic);
            notes.push_back(buf);
          } else if (!ml.ok()) {
            notes.push_back("the drifts were not identified against the candidates: " + std::string(ml.status().message()));
          } else {
            notes.push_back("no drift's σ and τ by likelihood are worth their parameters against the candidates");
          }
        }
        notes.push_back("the a-priori model lacks significant effects: the drift and reference-noise parameters "
                        "are not re-tuned on this model (they would absorb what the effects explain); they are "
                        "identified when the analysis starts from a model with the effects (baseline effects)");
        scanned = ScannedModel{std::move(*pass), std::move(found), std::move(found_notes)};
        deferred = true;
        break;
      }
      ident::RetargetResult step = ident::RetargetDrifts(base, *a_priori, drifts, options.settle_log_ratio,
                                                         options.monitor.family_wise_alpha);
      const bool reference_changed = ident::MatchReferenceNoise(pass->forward, options.monitor.family_wise_alpha,
                                                                step.model, &notes);
      // Nothing significant: the report's scan when nothing below re-tunes
      // the model (the unit's a-priori model fits), else a new one.
      if (may_defer) scanned = ScannedModel{std::move(*pass), std::move(found), std::move(found_notes)};
      base = step.model;
      // The correlation estimates replace the last ones, and the likelihood's
      // of a drift that the re-tuned model now resolves.
      std::erase_if(identified, [&](const ParameterEstimate& p) {
        return p.method == "ACF" || std::any_of(step.identified.begin(), step.identified.end(),
                                                [&](const ParameterEstimate& q) { return q.name == p.name; });
      });
      identified.insert(identified.end(), step.identified.begin(), step.identified.end());
      if (step.settled && !reference_changed) break;
      if (it + 1 == options.max_retarget_iterations) {
        notes.push_back("the identified drift parameters had not settled after " +
                        std::to_string(options.max_retarget_iterations) + " iterations");
      }
    }
    if (options.identify_drifts_by_likelihood && !deferred) {
      // The drifts' final values, by likelihood: correlation processing of
      // the smoothed estimates gives the drifts' structure and a start, but
      // the smoother's shrinkage biases its σ and τ low together along the
      // fit's ridge (docs/IDENTIFICATION.md, coverage); the likelihood's
      // estimates carry no such bias and their intervals cover the truth.
      // The unresolved set is done already when the deferral's competition
      // took it.
      for (const bool resolved_set : {false, true}) {
        if (!resolved_set && drifts_by_likelihood) continue;
        auto ml = identify_drifts(base, resolved_set);
        if (ml.ok()) WidenErrorsOrSay(epochs, *a_priori, *ml, notes);
        if (!ml.ok()) {
          notes.push_back("the drifts were not identified by likelihood: " + std::string(ml.status().message()));
        } else {
          ApplyDriftLikelihood(*ml, options.monitor.family_wise_alpha, a_priori_from_allan, base, identified, notes);
        }
      }
    }
  }

  Progress(options, 0.65, "missing-effect scan");
  if (scanned.has_value() && scanned->pass.model != base) scanned.reset();
  absl::StatusOr<ModelPass> a = scanned.has_value() ? absl::StatusOr<ModelPass>(std::move(scanned->pass))
                                                    : RunPass(run, epochs, base, spikes, options, /*with_scan=*/true);
  if (!a.ok()) return a.status();
  if (scanned.has_value()) notes.insert(notes.end(), scanned->notes.begin(), scanned->notes.end());
  const Findings found_a = scanned.has_value() ? std::move(scanned->found)
                                               : FindMissingEffects(run, epochs, *a, *a_priori, spikes, options, &notes);
  identified.insert(identified.begin(), removed_constants.begin(), removed_constants.end());
  AnalysisReport report_a = ReportOf(*a, found_a, run, options, identified, notes);

  Analysis out;
  if (request.discover) {
    // Model A stays whole for the comparison; `latest` holds the last step's pass.
    std::optional<ModelPass> latest;
    auto current = [&]() -> const ModelPass& { return latest.has_value() ? *latest : *a; };
    Findings found = found_a;
    AnalysisReport report = report_a;
    for (int step = 1; step <= options.max_discovery_steps; ++step) {
      const EffectCandidate* top = NextDiscovery(found, options);
      if (top == nullptr) break;
      Progress(options, 0.7 + 0.3 * step / (options.max_discovery_steps + 1), "discovery: adding " + top->name);
      auto extended = ExtendModel(run, current().model, {top->name}, current(), found, options);
      if (!extended.ok()) return extended.status();
      auto next = RunPass(run, epochs, *extended, spikes, options, /*with_scan=*/true);
      if (!next.ok()) return next.status();
      Findings next_found = FindMissingEffects(run, epochs, *next, *a_priori, spikes, options, &notes);
      identified = WithTakenStructures(std::move(identified), next->model, found);
      AnalysisReport next_report = ReportOf(*next, next_found, run, options, identified, notes);
      DiscoveryStep d;
      d.step = step;
      d.effect = top->name;
      d.statistic = top->statistic;
      d.p_value = top->p_value_holm;
      d.unit = top->unit;
      d.estimate = top->estimate;
      d.std_error = top->std_error;
      // The added terms' estimates in the model after the step (one for a
      // term, one per axis or pair for a family). The step's single value is
      // the term's, or for a family its most significant term's (largest
      // |estimate| / SE): a family has no one magnitude.
      double largest_z = -1.0;
      for (const ParameterEstimate& e : next_report.identified) {
        if (e.method != "FILTER" || !SelectorCovers(top->name, e.name)) continue;
        d.estimates.push_back(e);
        const double z = e.std_error > 0.0 ? std::abs(e.value) / e.std_error : 0.0;
        if (e.name == top->name || z > largest_z) {
          largest_z = e.name == top->name ? std::numeric_limits<double>::infinity() : z;
          d.estimate = e.value;
          d.std_error = e.std_error;
        }
      }
      d.nis_mean = next_report.nis_mean;
      d.log_likelihood = next_report.log_likelihood;
      d.aic = next_report.aic;
      d.bic = next_report.bic;
      d.channels = next_report.channels;
      report.discovery.push_back(d);
      next_report.discovery = report.discovery;
      latest = std::move(*next);
      found = std::move(next_found);
      report = std::move(next_report);
    }
    if (!report.discovery.empty()) {
      std::vector<std::string> added;
      for (const DiscoveryStep& d : report.discovery) added.push_back(d.effect);
      report.comparison = Compare(*a, current(), report_a, report, PredictedLikelihoodRatio(*a, added, found_a));
    }
    out.report = std::move(report);
    out.model = current().model;
    out.base_report = std::move(report_a);
    if (options.keep_series) FillSeries(current(), out.series);
  } else if (!request.add_effects.empty()) {
    Progress(options, 0.8, "model with the added effects");
    auto extended = ExtendModel(run, base, request.add_effects, *a, found_a, options);
    if (!extended.ok()) return extended.status();
    auto b = RunPass(run, epochs, *extended, spikes, options, /*with_scan=*/true);
    if (!b.ok()) return b.status();
    const Findings found_b = FindMissingEffects(run, epochs, *b, *a_priori, spikes, options, &notes);
    out.report = ReportOf(*b, found_b, run, options, WithTakenStructures(identified, b->model, found_a), notes);
    const std::vector<std::string> added = [&] {
      std::vector<std::string> names;
      for (const std::string& e : b->model.EffectNames()) {
        if (a->model.FindEffect(*ParseEffectSelector(e)->begin()) < 0) names.push_back(e);
      }
      return names;
    }();
    out.report.comparison = Compare(*a, *b, report_a, out.report, PredictedLikelihoodRatio(*a, added, found_a));
    out.model = b->model;
    out.base_report = std::move(report_a);
    if (options.keep_series) FillSeries(*b, out.series);
  } else {
    out.report = std::move(report_a);
    out.model = a->model;
    if (options.keep_series) FillSeries(*a, out.series);
  }
  out.report.allan = std::move(allan);
  Progress(options, 1.0, "done");
  return out;
}

}  // namespace insdiag::engine
