#include "insdiag/engine/analysis.h"

#include <cmath>
#include <numbers>

#include "insdiag/engine/filter/smoother.h"

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

void FillSeries(const ForwardPass& fw, const SmoothedPass& sm, const MonitorResult& mon, const StateLayout& layout,
                AnalysisSeries& series) {
  const int K = fw.epochs();
  series.time_s = fw.epoch_time_s;
  series.measured = fw.z;
  series.residual = fw.innovation;
  series.predicted = fw.z - fw.innovation;
  series.sigma = fw.innovation_variance.cwiseSqrt();
  series.window_ratio = mon.window_ratio;
  const int m = layout.sensor_count();
  const int b = layout.sensor_begin();
  series.state_names.clear();
  for (const SensorState& s : layout.sensor_states()) series.state_names.push_back(s.name);
  series.forward = fw.x_filt.middleCols(b, m);
  series.smoothed = sm.x.middleCols(b, m);
  series.smoothed_sigma = sm.variance.middleCols(b, m).cwiseSqrt();
  series.backward = sm.backward_x.middleCols(b, m);
  series.discrepancy = sm.discrepancy.middleCols(b, m);
  (void)K;
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

absl::Status AddEffects(const BenchRun& run, const std::vector<std::string>& selectors, double update_interval_s,
                        double diffuse_prior_scale, ErrorModel& model) {
  for (const std::string& selector : selectors) {
    auto terms = ParseEffectSelector(selector);
    if (!terms.ok()) return terms.status();
    for (const EffectTerm& term : *terms) {
      if (model.FindEffect(term) >= 0) continue;
      ModelEffect e;
      e.term = term;
      const SensorTriadModel& triad = term.family->sensor == Sensor::kGyro ? model.gyro : model.acc;
      // The sensor's white noise averaged over one update interval: the size of
      // error the data resolve in one step.
      const double noise = triad.white_noise_density.maxCoeff() / std::sqrt(update_interval_s);
      const double drift = std::max({triad.bias[0].sigma, triad.bias[1].sigma, triad.bias[2].sigma});
      const double scale = diffuse_prior_scale * std::max(noise, drift);
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

absl::StatusOr<Analysis> Analyze(const BenchRun& input, const AnalysisRequest& request,
                                 const AnalysisOptions& options) {
  if (auto st = options.Validate(); !st.ok()) return st;
  if (input.samples.size() < 2) return absl::InvalidArgumentError("the run has fewer than two samples");
  Analysis out;
  Progress(options, 0.0, "screening samples");
  BenchRun run = input;
  const std::vector<SampleOutlier> spikes = ScreenAndRepairSpikes(run, options.screening);

  auto model = APrioriModel(run, request.nominal, options.reference);
  if (!model.ok()) return model.status();
  if (auto st = AddEffects(run, request.add_effects, options.filter.update_interval_s,
                           options.diffuse_prior_scale, *model);
      !st.ok()) {
    return st;
  }
  out.model = *model;
  const StateLayout layout(out.model);

  Progress(options, 0.05, "forward filter");
  auto forward = RunForwardFilter(run, out.model, options.filter);
  if (!forward.ok()) return forward.status();
  Progress(options, 0.6, "smoother");
  auto smoothed = RunSmoother(*forward);
  if (!smoothed.ok()) return smoothed.status();
  Progress(options, 0.8, "monitoring");
  MonitorResult monitor = Monitor(*forward, *smoothed, layout, spikes, options.monitor);

  AnalysisReport& r = out.report;
  r.verdict = monitor.verdict;
  r.model_effects = out.model.EffectNames();
  r.parameter_count = out.model.ParameterCount();
  r.channels = monitor.channels;
  r.nis_mean = monitor.nis_mean;
  r.nis_band_low = monitor.nis_band_low;
  r.nis_band_high = monitor.nis_band_high;
  r.log_likelihood = forward->log_likelihood;
  r.scalar_updates = forward->scalar_updates;
  r.aic = 2.0 * r.parameter_count - 2.0 * r.log_likelihood;
  r.bic = r.parameter_count * std::log(static_cast<double>(std::max(1, r.scalar_updates))) - 2.0 * r.log_likelihood;
  r.gamma2 = monitor.gamma2;
  r.eta2 = monitor.eta2;
  r.faults = monitor.faults;
  r.localisation = monitor.localisation;
  r.discrepancies = monitor.discrepancies;
  r.duration_s = run.DurationS();
  r.samples = run.samples.size();
  r.sample_rate_hz = 1.0 / run.NominalIntervalS();
  r.update_interval_s = options.filter.update_interval_s;
  if (options.keep_series) FillSeries(*forward, *smoothed, monitor, layout, out.series);
  Progress(options, 1.0, "done");
  return out;
}

}  // namespace insdiag::engine
