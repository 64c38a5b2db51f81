#include "insdiag/engine/ident/retarget.h"

#include <algorithm>
#include <cmath>

#include "insdiag/engine/model/drift_axis.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/model/parameter_field.h"
#include "insdiag/engine/numerics/golden_section.h"
#include "insdiag/engine/numerics/parallel_map.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine::ident {
namespace {

double EpochInterval(const ForwardPass& fw) {
  return fw.epochs() > 1 ? (fw.epoch_time_s.back() - fw.epoch_time_s.front()) / (fw.epochs() - 1) : 1.0;
}

}  // namespace

SmootherOptions DriftSmootherOptions(const ErrorModel& model, const StateLayout& layout, const ForwardPass& fw,
                                     const CorrelationOptions& options) {
  SmootherOptions o;
  for (int i = 0; i < 6; ++i) o.error_acf_states.push_back(layout.gyro_bias() + i);
  double tau = 0.0;
  for (const auto* triad : {&model.gyro, &model.acc}) {
    for (const GaussMarkov& gm : triad->bias) tau = std::max(tau, gm.tau_s);
  }
  // The correlation processing looks at lags up to a few τ and a share of the run.
  const int by_tau = static_cast<int>(2.0 * options.max_lag_in_tau * tau / EpochInterval(fw)) + 1;
  o.error_acf_max_lag = std::min(static_cast<int>(options.max_lag_fraction * fw.epochs()), by_tau);
  return o;
}

std::vector<DriftCorrelation> CorrelateDrifts(const ForwardPass& fw, const SmoothedPass& sm, const StateLayout& layout,
                                              const CorrelationOptions& options, std::vector<std::string>* notes) {
  const double dt = EpochInterval(fw);
  // The six drifts' fits are independent: on every core, read in order.
  auto analyses = numerics::ParallelMap(6, [&](std::size_t i) {
    const int state = layout.gyro_bias() + static_cast<int>(i);
    std::vector<double> series(static_cast<size_t>(fw.epochs()));
    for (int k = 0; k < fw.epochs(); ++k) series[static_cast<size_t>(k)] = sm.x(k, state);
    const std::vector<double> empty;
    const std::vector<double>& error_acf = i < sm.error_autocovariance.size() ? sm.error_autocovariance[i] : empty;
    return AnalyseCorrelation(series, error_acf, dt, options);
  });
  std::vector<DriftCorrelation> out;
  for (int i = 0; i < 6; ++i) {
    const int state = layout.gyro_bias() + i;
    const SensorState& drift = layout.sensor_states()[static_cast<size_t>(state - layout.sensor_begin())];
    auto& analysis = analyses[static_cast<size_t>(i)];
    if (!analysis.ok()) {
      if (notes != nullptr) notes->push_back(drift.name + ": no correlation processing (" + std::string(analysis.status().message()) + ")");
      continue;
    }
    const FamilyFit* exponential = analysis->Fit(CorrelationFamily::kExponential);
    if (notes != nullptr && exponential != nullptr && exponential->usable &&
        exponential->stopped_at_iteration_cap) {
      notes->push_back(drift.name +
                       ": the exponential fit of the smoothed drift's autocorrelation stopped at its "
                       "iteration cap before converging; its σ and τ are the last iterate's");
    }
    out.push_back({drift.name, drift.sensor, drift.axis, *std::move(analysis)});
  }
  return out;
}

RetargetResult RetargetDrifts(const ErrorModel& current, const ErrorModel& a_priori,
                              const std::vector<DriftCorrelation>& drifts, double settle_log_ratio, double alpha) {
  RetargetResult r;
  r.model = current;
  const double reject = stats::ChiSquareQuantile(1.0 - alpha, 2.0);
  for (const DriftCorrelation& d : drifts) {
    const FamilyFit* fit = d.analysis.Fit(CorrelationFamily::kExponential);
    if (!d.analysis.resolved || fit == nullptr || !fit->usable) continue;
    const bool gyro = d.sensor == Sensor::kGyro;
    GaussMarkov& gm = (gyro ? r.model.gyro : r.model.acc).bias[static_cast<size_t>(d.axis)];
    const GaussMarkov& prior = (gyro ? a_priori.gyro : a_priori.acc).bias[static_cast<size_t>(d.axis)];
    const FittedParameter& sigma = fit->parameters[0];
    const FittedParameter& tau = fit->parameters[1];
    // Does the fit reject the a-priori (σ₀, τ₀)?
    bool rejects = true;
    const Eigen::Matrix2d C = fit->log_covariance.topLeftCorner<2, 2>();
    if (C.allFinite() && prior.sigma > 0.0 && prior.tau_s > 0.0) {
      const Eigen::Vector2d d_log(std::log(sigma.value / prior.sigma), std::log(tau.value / prior.tau_s));
      rejects = d_log.dot(C.ldlt().solve(d_log)) > reject;
    }
    const GaussMarkov target = rejects ? GaussMarkov{sigma.value, tau.value} : prior;
    for (const auto& [value, new_value, estimate] :
         {std::tuple{&gm.sigma, target.sigma, &sigma}, std::tuple{&gm.tau_s, target.tau_s, &tau}}) {
      const double change = std::abs(std::log(new_value / std::max(*value, 1e-300)));
      const bool within_error = std::isfinite(estimate->std_error) && std::abs(new_value - *value) < estimate->std_error;
      if (change > settle_log_ratio && !within_error) r.settled = false;
      *value = new_value;
    }
    for (const auto& [estimate, prior_value, suffix, unit] :
         {std::tuple{&sigma, prior.sigma, ParameterField::kSigma, UnitsOf(d.sensor).rate},
          std::tuple{&tau, prior.tau_s, ParameterField::kTau, std::string_view("s")}}) {
      ParameterEstimate p;
      p.name = ParameterName(d.state, suffix);
      p.value = estimate->value;
      p.std_error = estimate->std_error;
      p.ci95_low = estimate->ci95_low;
      p.ci95_high = estimate->ci95_high;
      p.method = EstimationMethod::kAutocorrelation;
      p.unit = std::string(unit);
      p.a_priori = prior_value;
      r.identified.push_back(p);
    }
  }
  return r;
}

std::vector<ParameterEstimate> ApplyAllanNoise(const AllanResult& allan, const ErrorModel& a_priori, ErrorModel& model,
                                               double alpha) {
  std::vector<ParameterEstimate> used;
  // The a-priori value stands unless the Allan fit rejects it, as for the
  // drifts (RetargetDrifts). The fit's terms trade off against each other:
  // an effect the model lacks (a thermal drift, say) is taken up by the
  // rate-random-walk term, whose correlation with the white term leaves that
  // one uncertain by several percent. Taking such an estimate as exact when
  // the datasheet's value agrees with it within its error throws the better
  // value away, and the filter's NIS then reads (N₀/N̂)² — 1.14 for a 6% low
  // VRW — whatever effects are added (acc_temp_coeff on the thermal profile,
  // tests/engine/effect_finder_test.cc).
  const double reject = stats::ChiSquareQuantile(1.0 - alpha, 1.0);
  auto rejects = [&](double value, double std_error, double prior) {
    if (!(prior > 0.0)) return true;  // nothing a-priori: the fit is all there is
    // Wald statistic of ln(value/prior) with var(ln value) ≈ (σ/value)².
    const double z = std::log(value / prior) / (std_error / value);
    return z * z > reject;
  };
  for (const AllanChannel& ch : allan.channels) {
    SensorTriadModel& triad = ch.sensor == Sensor::kGyro ? model.gyro : model.acc;
    const SensorTriadModel& prior = ch.sensor == Sensor::kGyro ? a_priori.gyro : a_priori.acc;
    const AllanTermEstimate& n = ch.fit[AllanParameter::kWhiteDensity];
    const AllanTermEstimate& q = ch.fit[AllanParameter::kQuantization];
    if (n.included && n.value > 0.0 && std::isfinite(n.std_error) &&
        rejects(n.value, n.std_error, prior.white_noise_density[ch.axis])) {
      triad.white_noise_density[ch.axis] = n.value;
      ParameterEstimate p;
      p.name = WhiteNoiseName({ch.sensor, ch.axis});
      p.value = n.value;
      p.std_error = n.std_error;
      p.method = EstimationMethod::kAllan;
      p.unit = std::string(UnitsOf(ch.sensor).white_density);
      p.a_priori = prior.white_noise_density[ch.axis];
      used.push_back(p);
    }
    if (ch.QuantisationIsCounted()) {
      // The counter's quantum is read, not estimated: it stands.
      triad.quantization[ch.axis] = ch.Quantisation();
    } else if (q.included && q.value > 0.0 && std::isfinite(q.std_error) &&
               rejects(q.value, q.std_error, prior.quantization[ch.axis])) {
      triad.quantization[ch.axis] = q.value;
    }
  }
  return used;
}

ReferenceNoiseExcess ScreenReferenceNoise(const ForwardPass& fw, double alpha,
                                          const ErrorModel& model) {
  ReferenceNoiseExcess out;
  const int K = fw.epochs();
  if (K == 0) return out;
  for (size_t group = 0; group < kReferenceChannelGroups.size(); ++group) {
    const ReferenceChannelGroup& g = kReferenceChannelGroups[group];
    double nis = 0.0, excess = 0.0, lag1 = 0.0;
    for (int c = g.first_channel; c < g.first_channel + g.channel_count; ++c) {
      double previous = 0.0;
      for (int k = 0; k < K; ++k) {
        const double nu = fw.innovation(k, c);
        const double S = fw.innovation_variance(k, c);
        const double normalised = nu / std::sqrt(S);
        nis += normalised * normalised;
        lag1 += previous * normalised;
        previous = normalised;
        excess += nu * nu - S;  // mean(ν²) − mean(S) = r̂ − r
      }
    }
    const int n = g.channel_count * K;
    if (nis / n <= stats::ChiSquareQuantile(1.0 - alpha, n) / n) continue;
    // Reference noise the model lacks is white: a filter that trusts the
    // reference too much overreacts, and its innovations alternate (lag-one
    // correlation ≤ 0). Innovations that persist — positively correlated —
    // are a systematic effect the model lacks, which the effect finder must
    // see, not a noise to be widened away (Mehra, IEEE Trans. AC-15(2), 1970:
    // covariance matching presumes the model's structure is right).
    const double rho1 = lag1 / nis;
    if (rho1 > stats::NormalQuantile(1.0 - alpha) / std::sqrt(static_cast<double>(n))) continue;
    const double sigma = model.reference.*g.sigma;
    const double r = sigma * sigma + excess / n;
    if (!(r > sigma * sigma)) continue;
    out.matched_sigma[group] = std::sqrt(r);
  }
  return out;
}

bool UnresolvedNoise::Any() const {
  for (const auto* flags : {&gyro_white, &acc_white, &gyro_drift, &acc_drift, &gyro_drift_seed, &acc_drift_seed,
                            &gyro_white_seed, &acc_white_seed}) {
    for (bool f : *flags) {
      if (f) return true;
    }
  }
  return false;
}

UnresolvedNoise UnresolvedAllanTerms(const AllanResult& allan) {
  UnresolvedNoise u;
  for (const AllanChannel& ch : allan.channels) {
    const auto axis = static_cast<size_t>(ch.axis);
    const bool gyro = ch.sensor == Sensor::kGyro;
    // The same tests as ErrorModelFromAllan's branches.
    const bool white_resolved = ch.fit[AllanParameter::kWhiteDensity].included;
    (gyro ? u.gyro_white : u.acc_white)[axis] = !white_resolved;
    (gyro ? u.gyro_white_seed : u.acc_white_seed)[axis] = white_resolved;
    const bool bound = !ch.fit[AllanParameter::kMarkovSigma].included &&
                       !ch.fit[AllanParameter::kBiasInstability].included &&
                       !ch.fit[AllanParameter::kRateRandomWalk].included;
    (gyro ? u.gyro_drift : u.acc_drift)[axis] = bound;
    (gyro ? u.gyro_drift_seed : u.acc_drift_seed)[axis] = !bound;
  }
  return u;
}

namespace {

struct ScaledTerm {
  double* value;      // in the working model
  double bound;       // the value it started from
  std::string name;
  std::string unit;
};

struct Group {
  std::string name;
  std::vector<ScaledTerm> terms;
  double log_scale = 0.0;
  double max_scale = 1.0;
};

// The groups of noise terms whose common scale is searched: the white noises
// and drifts `which` names, each group's terms pointing into `m`.
std::vector<Group> GroupsToScale(ErrorModel& m, const UnresolvedNoise& which,
                                 const NoiseScaleOptions& options) {
  std::vector<Group> groups;
  auto add_group = [&](const char* name, const std::array<bool, 3>& flags, Sensor sensor,
                       bool drift, double max_scale) {
    SensorTriadModel& triad = sensor == Sensor::kGyro ? m.gyro : m.acc;
    Group g;
    g.name = name;
    g.max_scale = max_scale;
    for (size_t a = 0; a < 3; ++a) {
      if (!flags[a]) continue;
      double* v = drift ? &triad.bias[a].sigma : &triad.white_noise_density[static_cast<Eigen::Index>(a)];
      // A zero term has no scale to find.
      if (!(*v > 0.0)) continue;
      const int axis = static_cast<int>(a);
      const DriftAxis sensor_axis{sensor, axis};
      g.terms.push_back(
          {v, *v, drift ? DriftSigmaName(sensor_axis) : WhiteNoiseName(sensor_axis),
           std::string(drift ? UnitsOf(sensor).rate : UnitsOf(sensor).white_density)});
    }
    if (!g.terms.empty()) groups.push_back(std::move(g));
  };
  const double bound = options.max_scale, seed = options.max_seed_scale;
  add_group("gyro white", which.gyro_white, Sensor::kGyro, false, bound);
  add_group("acc white", which.acc_white, Sensor::kAccelerometer, false, bound);
  add_group("gyro drift", which.gyro_drift, Sensor::kGyro, true, bound);
  add_group("acc drift", which.acc_drift, Sensor::kAccelerometer, true, bound);
  add_group("gyro drift seed", which.gyro_drift_seed, Sensor::kGyro, true, seed);
  add_group("acc drift seed", which.acc_drift_seed, Sensor::kAccelerometer, true, seed);
  add_group("gyro white seed", which.gyro_white_seed, Sensor::kGyro, false, seed);
  add_group("acc white seed", which.acc_white_seed, Sensor::kAccelerometer, false, seed);
  return groups;
}

void ApplyScale(Group& g, double log_scale) {
  g.log_scale = log_scale;
  for (ScaledTerm& t : g.terms) *t.value = t.bound * std::exp(log_scale);
}

}  // namespace

absl::StatusOr<NoiseScaleResult> ScaleUnresolvedNoise(const EpochRun& run, const ErrorModel& model,
                                                      const UnresolvedNoise& which,
                                                      const NoiseScaleOptions& options) {
  if (!(options.min_scale > 0.0 && options.max_scale > options.min_scale &&
        options.log_tolerance > 0.0)) {
    return absl::InvalidArgumentError("noise scale options out of range");
  }
  NoiseScaleResult out;
  out.model = model;
  ErrorModel& m = out.model;
  std::vector<Group> groups = GroupsToScale(m, which, options);
  absl::Status failure = absl::OkStatus();
  auto log_likelihood = [&]() {
    auto fw = RunForwardFilter(run, m);
    ++out.filter_passes;
    if (!fw.ok()) {
      failure = fw.status();
      return -std::numeric_limits<double>::infinity();
    }
    return fw->log_likelihood;
  };
  out.log_likelihood_before = log_likelihood();
  if (!failure.ok()) return failure;
  double best = out.log_likelihood_before;
  const double lo_limit = std::log(options.min_scale);
  for (int sweep = 0; sweep < options.sweeps && !groups.empty(); ++sweep) {
    for (Group& g : groups) {
      auto at = [&](double log_scale) {
        ApplyScale(g, log_scale);
        return log_likelihood();
      };
      // ℓ is unimodal in a variance scale when the structure is right.
      const auto top = numerics::GoldenSectionMaximum(lo_limit, std::log(g.max_scale), g.log_scale,
                                                      best, options.log_tolerance, at);
      if (!failure.ok()) return failure;
      best = top.first;
      ApplyScale(g, top.second);
    }
  }
  // Standard errors of ln ŝ from the curvature of ℓ (observed information),
  // central second difference with step h.
  const double h = 0.1;
  for (Group& g : groups) {
    NoiseScaleGroup r;
    r.name = g.name;
    r.scale = std::exp(g.log_scale);
    const double x = g.log_scale;
    const double hi_limit = std::log(g.max_scale);
    r.at_limit = x <= lo_limit + options.log_tolerance || x >= hi_limit - options.log_tolerance;
    ApplyScale(g, x + h);
    const double up = log_likelihood();
    ApplyScale(g, x - h);
    const double down = log_likelihood();
    ApplyScale(g, x);
    const double curvature = (up - 2.0 * best + down) / (h * h);
    if (curvature < 0.0 && !r.at_limit) r.log_std_error = 1.0 / std::sqrt(-curvature);
    for (const ScaledTerm& t : g.terms) {
      r.terms.push_back(t.name);
      ParameterEstimate p;
      p.name = t.name;
      p.value = *t.value;
      p.std_error = p.value * r.log_std_error;
      p.ci95_low = p.value * std::exp(-1.96 * r.log_std_error);
      p.ci95_high = p.value * std::exp(1.96 * r.log_std_error);
      p.method = EstimationMethod::kMaximumLikelihood;
      p.unit = t.unit;
      p.a_priori = t.bound;
      out.identified.push_back(p);
    }
    out.groups.push_back(r);
  }
  if (!failure.ok()) return failure;
  out.log_likelihood_after = best;
  return out;
}

}  // namespace insdiag::engine::ident
