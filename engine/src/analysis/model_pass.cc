#include "analysis/model_pass.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "insdiag/engine/ident/correlation.h"
#include "insdiag/engine/ident/retarget.h"
#include "insdiag/engine/monitor/sample_screening.h"

namespace insdiag::engine::pipeline {
namespace {

// Constant effects enter the filter as states with a diffuse prior N(0, Σ);
// the filter's log-likelihood is then the marginal one, lower than the
// likelihood at the parameters' maximum by the prior's weight. With the final
// posterior N(x, P) of the constants and the data's information I = P⁻¹ − Σ⁻¹,
// in Σ-whitened coordinates (Σ = LLᵀ, Ĩ = Lᵀ I L with eigenpairs λ_i, u_i,
// g = Lᵀ P⁻¹ x):
//   ℓ_max − ℓ_marginal = ½ Σ_i [ln(1 + λ_i) + (u_iᵀ g)² / (λ_i (1 + λ_i))]
// over the directions the data inform (Harvey, Forecasting, Structural Time
// Series Models and the Kalman Filter, 1989, §3.4: the diffuse likelihood).
// A warm-up's start value decays with no process noise, so at the end its
// posterior and its prior are the start's scaled by one factor e^{−T/τ}:
// the same correction, with the prior scaled, where a double still holds it.
double ProfileCorrection(const ForwardPass& fw, const ErrorModel& model, const StateLayout& layout) {
  std::vector<int> states;
  std::vector<double> prior_sigma;
  const double run_s = fw.epochs() > 0 ? fw.epoch_time_s.back() - fw.epoch_start_s.front() : 0.0;
  for (const SensorState& s : layout.sensor_states()) {
    if ((s.dynamics != StateDynamics::kConstant && s.dynamics != StateDynamics::kDecaying) || s.effect < 0) continue;
    const ModelEffect& e = model.effects[static_cast<size_t>(s.effect)];
    double sigma = e.prior_sigma[static_cast<size_t>(s.parameter)];
    if (s.dynamics == StateDynamics::kDecaying) {
      constexpr double kSmallestDecayHeld = 1e-100;
      const double decay = std::exp(-run_s / e.time_constant_s);
      if (!(decay > kSmallestDecayHeld)) continue;
      sigma *= decay;
    }
    states.push_back(s.index);
    prior_sigma.push_back(sigma);
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

}  // namespace

absl::StatusOr<ModelPass> RunPass(const BenchRun& run, const EpochRun& epochs, const ErrorModel& model,
                                  const SampleScreening& samples, const AnalysisOptions& options,
                                  bool with_scan) {
  ModelPass pass;
  pass.model = model;
  pass.layout = std::make_unique<StateLayout>(pass.model);
  const int segment_epochs =
      std::max(1, static_cast<int>(std::lround(options.segment_s / options.filter.update_interval_s)));
  // The warm-ups' scan rides the same pass as the constants' (finder/warm_up_scan.h).
  std::optional<WarmUpScoreObserver> warm_up_scan;
  if (with_scan) {
    pass.scan = std::make_unique<ScoreTestObserver>(*pass.layout, epochs, AbsentConstantCandidates(pass.model), segment_epochs);
    std::vector<double> taus = WarmUpTimeConstants(epochs, WarmUpGrid{.shortest_s = options.onset_scan.min_side_s});
    if (!taus.empty()) warm_up_scan.emplace(*pass.layout, epochs, std::move(taus), &samples.bench_motion);
  }
  FilterObservers observers({pass.scan.get(), warm_up_scan ? &*warm_up_scan : nullptr});
  auto forward = RunForwardFilter(epochs, pass.model, &observers);
  if (!forward.ok()) return forward.status();
  pass.forward = *std::move(forward);
  auto smoothed = RunSmoother(pass.forward, ident::DriftSmootherOptions(pass.model, *pass.layout, pass.forward,
                                                                        options.correlation));
  if (!smoothed.ok()) return smoothed.status();
  pass.smoothed = *std::move(smoothed);
  pass.monitor = Monitor(pass.forward, pass.smoothed, *pass.layout, samples, options.monitor);
  pass.log_likelihood = pass.forward.log_likelihood + ProfileCorrection(pass.forward, pass.model, *pass.layout);
  if (with_scan) {
    pass.segment_motion = SegmentMotion(run, pass.forward, segment_epochs);
    pass.onsets = ScanOnsets(pass.forward, *pass.layout, epochs, AbsentFaultTerms(pass.model), options.onset_scan);
    if (warm_up_scan) pass.warm_ups = warm_up_scan->Fits(pass.model);
  }
  return pass;
}

absl::StatusOr<double> ProfileLogLikelihood(const EpochRun& epochs, const ErrorModel& model) {
  auto forward = RunForwardFilter(epochs, model);
  if (!forward.ok()) return forward.status();
  return ProfileLogLikelihood(*forward, model);
}

double ProfileLogLikelihood(const ForwardPass& forward, const ErrorModel& model) {
  return forward.log_likelihood + ProfileCorrection(forward, model, StateLayout(model));
}

double PriorSigmaAroundEstimate(double estimate, double std_error, const AnalysisOptions& options) {
  return options.estimated_prior_scale * std::max(std::abs(estimate), 3.0 * std_error);
}

ModelEffect FaultEffectAt(const EffectTerm& term, double onset_s, double estimate, double std_error,
                          const AnalysisOptions& options) {
  ModelEffect e;
  e.term = term;
  e.onset_s = onset_s;
  e.prior_sigma[0] = PriorSigmaAroundEstimate(estimate, std_error, options);
  return e;
}

void FillFit(const ModelPass& pass, const BenchRun& run, const AnalysisOptions& options, AnalysisReport& r) {
  const MonitorResult& m = pass.monitor;
  r.verdict = m.verdict;
  r.model_effects = pass.model.EffectNames();
  r.parameter_count = pass.model.ParameterCount();
  r.channels = m.channels;
  r.fit.nis_mean = m.nis_mean;
  r.nis_band_low = m.nis_band_low;
  r.nis_band_high = m.nis_band_high;
  r.fit.log_likelihood = pass.log_likelihood;
  r.scalar_updates = pass.forward.scalar_updates;
  r.fit.aic = 2.0 * r.parameter_count - 2.0 * r.fit.log_likelihood;
  r.fit.bic = r.parameter_count * std::log(static_cast<double>(std::max(1, r.scalar_updates))) -
              2.0 * r.fit.log_likelihood;
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

std::array<double, 2> RegressorRms(const BenchRun& run, const EffectTerm& term,
                                   const std::vector<std::array<double, 6>>* reference_inputs, bool full_scale) {
  std::array<double, 2> sum = {0.0, 0.0};
  double values[2];
  const double t0 = run.samples.front().temp_degc;
  double n = 0.0;
  for (size_t k = 0; k < run.samples.size(); ++k) {
    if (run.StartsSegment(k)) continue;
    const ImuSample& s = run.samples[k];
    RegressorInputs in;
    if (reference_inputs != nullptr) {
      const auto& r = (*reference_inputs)[k];
      in.gyro_rad_s = {r[0], r[1], r[2]};
      in.acc_mps2 = {r[3], r[4], r[5]};
      if (full_scale) {
        in.gyro_rad_s.setConstant(in.gyro_rad_s.norm());
        in.acc_mps2.setConstant(in.acc_mps2.norm());
      }
    } else {
      in.gyro_rad_s = s.gyro_rad_s;
      in.acc_mps2 = s.acc_mps2;
    }
    in.temperature_delta_degc = run.has_temperature ? s.temp_degc - t0 : 0.0;
    in.yaw_rad = s.ref_rpy_rad.z();
    EvaluateRegressor(term, in, values);
    for (int p = 0; p < term.family->parameters_per_term; ++p) sum[static_cast<size_t>(p)] += values[p] * values[p];
    n += 1.0;
  }
  if (n == 0.0) return {0.0, 0.0};
  return {std::sqrt(sum[0] / n), std::sqrt(sum[1] / n)};
}

// The reference inputs are known to within the input vector turned by the
// reference attitude's uncertainty (σ_att·|input|), and come from its
// trigonometry and the table motion's shape: an axis the table holds at right
// angles to gravity (z up: sin π; a turn about the vertical) reads 1e-16 to
// 1e-9 of g there, not 0. A reference excitation within either, as a fraction
// of the regressor's full scale (the inputs' whole magnitude on its axis), is
// no excitation.
constexpr double kReferenceRoundingFraction = 1e-9;

std::vector<ParameterEstimate> ConstantEffectEstimates(const ModelPass& pass, const BenchRun& run,
                                                       const std::vector<std::array<double, 6>>& reference_measurements) {
  std::vector<ParameterEstimate> out;
  const int K = pass.forward.epochs();
  if (K == 0) return out;
  // Per effect (its parameters share one sweep over the samples): the
  // regressor's RMS over the measured and over the reference inputs.
  struct EffectRms {
    int effect = -1;
    std::array<double, 2> measured{}, reference{}, full_scale{};
  };
  EffectRms rms;
  // A constant's filtered covariance at the end is its smoothed one.
  Eigen::MatrixXd P;
  UnpackSymmetric(pass.forward.P_filt.row(K - 1).data(), pass.forward.state_size, P);
  for (const SensorState& s : pass.layout->sensor_states()) {
    if (s.dynamics != StateDynamics::kConstant || s.effect < 0) continue;
    const ModelEffect& e = pass.model.effects[static_cast<size_t>(s.effect)];
    ParameterEstimate p;
    p.name = s.name;
    p.value = pass.forward.x_filt(K - 1, s.index);
    p.std_error = std::sqrt(pass.smoothed.variance(K - 1, s.index));
    p.method = EstimationMethod::kFilterState;
    p.unit = std::string(e.term.family->unit);
    if (rms.effect != s.effect) {
      rms = {s.effect, RegressorRms(run, e.term), RegressorRms(run, e.term, &reference_measurements),
             RegressorRms(run, e.term, &reference_measurements, /*full_scale=*/true)};
    }
    const auto& measured_rms = rms.measured;
    const auto& reference_rms = rms.reference;
    const auto k = static_cast<size_t>(s.parameter);
    // prior σ = scale / measured RMS (AddEffects): the same scale over what the table excited.
    const double scale = measured_rms[k] > 0.0 ? e.prior_sigma[k] * measured_rms[k] : e.prior_sigma[k];
    const double resolved =
        std::max(pass.model.reference.attitude_sigma_rad, kReferenceRoundingFraction) * rms.full_scale[k];
    const bool excited = reference_rms[k] > resolved;
    p.prior_std = excited ? scale / reference_rms[k] : std::numeric_limits<double>::infinity();
    p.max_correlation = 0.0;
    for (const SensorState& other : pass.layout->sensor_states()) {
      // Among the constants: a slow drift state shares a constant's
      // signal over any run shorter than its correlation time, whatever the table did.
      if (other.dynamics != StateDynamics::kConstant || other.index == s.index) continue;
      if (!(P(s.index, s.index) > 0.0) || !(P(other.index, other.index) > 0.0)) continue;
      const double rho = P(s.index, other.index) / std::sqrt(P(s.index, s.index) * P(other.index, other.index));
      if (std::abs(rho) > std::abs(p.max_correlation)) {
        p.max_correlation = rho;
        p.correlated_with = other.name;
      }
    }
    out.push_back(p);
  }
  return out;
}
std::vector<ParameterEstimate> WarmUpEstimates(const ModelPass& pass) {
  std::vector<ParameterEstimate> out;
  const ForwardPass& fw = pass.forward;
  if (fw.epochs() == 0) return out;
  for (const SensorState& s : pass.layout->sensor_states()) {
    if (s.dynamics != StateDynamics::kDecaying) continue;
    const ModelEffect& e = pass.model.effects[static_cast<size_t>(s.effect)];
    // The state at the first epoch is the start value decayed over one interval.
    const double back_to_start = std::exp((fw.epoch_time_s.front() - fw.epoch_start_s.front()) / e.time_constant_s);
    ParameterEstimate p;
    p.name = s.name;
    p.value = pass.smoothed.x(0, s.index) * back_to_start;
    p.std_error = std::sqrt(pass.smoothed.variance(0, s.index)) * back_to_start;
    p.method = EstimationMethod::kFilterState;
    p.unit = std::string(e.term.family->unit);
    p.prior_std = e.prior_sigma[0];
    out.push_back(std::move(p));
  }
  return out;
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

}  // namespace insdiag::engine::pipeline
