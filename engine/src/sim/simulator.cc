#include "insdiag/engine/sim/simulator.h"

#include <charconv>
#include <cmath>
#include <numbers>
#include <random>

#include "insdiag/engine/nav/rotation.h"
#include "insdiag/engine/nav/strapdown.h"
#include "insdiag/engine/nav/wgs84.h"

namespace insdiag::engine::sim {
namespace {

// Interval integrals of the table's true motion over (a, b].
struct IntervalIntegrals {
  Eigen::Vector3d angle_rad = Eigen::Vector3d::Zero();  // ∫ ω_ib^b dt
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();  // ∫ f^b dt
  double sin_yaw_s = 0.0;  // ∫ sin ψ dt
  double cos_yaw_s = 0.0;
};

void AccumulateGaussLegendre(const TableMotion& motion, const Eigen::Vector3d& w_ie_n,
                             const Eigen::Vector3d& g_n, double a, double b, IntervalIntegrals& out) {
  // 3-point Gauss–Legendre: exact for polynomials of degree 5 on [a, b].
  static const double kNode = std::sqrt(3.0 / 5.0);
  static constexpr double kWeights[3] = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
  const double mid = 0.5 * (a + b);
  const double half = 0.5 * (b - a);
  const double nodes[3] = {mid - half * kNode, mid, mid + half * kNode};
  for (int q = 0; q < 3; ++q) {
    const double t = nodes[q];
    const double w = half * kWeights[q];
    const Eigen::Matrix3d C_b_n = motion.BodyToNed(t);
    const Eigen::Vector3d w_ib_b = motion.TableRateBody(t) + C_b_n.transpose() * w_ie_n;
    const Eigen::Vector3d f_b = C_b_n.transpose() * (-g_n);
    const double yaw = std::atan2(C_b_n(1, 0), C_b_n(0, 0));
    out.angle_rad += w * w_ib_b;
    out.velocity_mps += w * f_b;
    out.sin_yaw_s += w * std::sin(yaw);
    out.cos_yaw_s += w * std::cos(yaw);
  }
}

// State of one random effect's process.
struct RandomEffectState {
  const TrueEffect* effect;
  Eigen::Vector2d x = Eigen::Vector2d::Zero();
};

// Carries the sub-quantum remainder of each axis (IEEE Std 952, Annex C).
class Quantizer {
 public:
  explicit Quantizer(const Eigen::Vector3d& coefficient) : quantum_(coefficient * std::sqrt(12.0)) {}
  Eigen::Vector3d Apply(const Eigen::Vector3d& mean, double dt) {
    Eigen::Vector3d out = mean;
    for (int i = 0; i < 3; ++i) {
      if (quantum_[i] <= 0.0) continue;
      const double increment = mean[i] * dt + remainder_[i];
      const double counts = std::round(increment / quantum_[i]);
      remainder_[i] = increment - counts * quantum_[i];
      out[i] = counts * quantum_[i] / dt;
    }
    return out;
  }

 private:
  Eigen::Vector3d quantum_;
  Eigen::Vector3d remainder_ = Eigen::Vector3d::Zero();
};

// Advances the base drifts (seed eq. 5, exact discretisation) and the random
// effects' processes over one sample interval.
void AdvanceDrifts(const SimulatedUnit& unit, double dt, Eigen::Vector3d& gyro_gm, Eigen::Vector3d& acc_gm,
                   std::vector<RandomEffectState>& random_states, std::mt19937_64& rng,
                   std::normal_distribution<double>& normal) {
  for (int i = 0; i < 3; ++i) {
    for (auto [triad, drift] : {std::pair{&unit.gyro, &gyro_gm}, std::pair{&unit.acc, &acc_gm}}) {
      const GaussMarkov& gm = triad->bias[i];
      if (gm.sigma <= 0.0) continue;
      const double phi = std::exp(-dt / gm.tau_s);
      (*drift)[i] = phi * (*drift)[i] + gm.sigma * std::sqrt(1.0 - phi * phi) * normal(rng);
    }
  }
  for (RandomEffectState& s : random_states) {
    const TrueEffect& e = *s.effect;
    if (e.term.family->process == RandomProcess::kRandomWalk) {
      s.x[0] += e.random_walk_density * std::sqrt(dt) * normal(rng);
      continue;
    }
    if (e.term.family->process == RandomProcess::kDecayFromStart) {
      s.x[0] *= std::exp(-dt / e.time_constant_s);
      continue;
    }
    // Rotating damped pair: x ← e^{−αΔt} R(βΔt) x + w, E[wwᵀ] = σ²(1 − e^{−2αΔt}) I.
    const double decay = std::exp(-e.second_order_alpha_per_s * dt);
    const double c = std::cos(e.second_order_beta_rad_s * dt);
    const double sn = std::sin(e.second_order_beta_rad_s * dt);
    const Eigen::Vector2d rotated(c * s.x[0] - sn * s.x[1], sn * s.x[0] + c * s.x[1]);
    const double q = e.second_order_sigma * std::sqrt(1.0 - decay * decay);
    s.x = decay * rotated + q * Eigen::Vector2d(normal(rng), normal(rng));
  }
}

double AxisMean(const Eigen::Vector3d& v) { return v.mean(); }
double AxisRms(const std::array<GaussMarkov, 3>& b, double GaussMarkov::*field) {
  double s = 0.0;
  for (const auto& g : b) s += (g.*field) * (g.*field);
  return std::sqrt(s / 3.0);
}

}  // namespace

absl::StatusOr<std::vector<double>> ParseNumberList(std::string_view text, std::string_view what) {
  std::vector<double> values;
  while (!text.empty()) {
    const size_t comma = text.find(',');
    const std::string_view item = text.substr(0, comma);
    double v = 0.0;
    const auto [ptr, ec] = std::from_chars(item.data(), item.data() + item.size(), v);
    if (ec != std::errc() || ptr != item.data() + item.size() || !std::isfinite(v)) {
      return absl::InvalidArgumentError(std::string(what) + ": '" + std::string(item) + "' is not a number");
    }
    values.push_back(v);
    if (comma == std::string_view::npos) break;
    text.remove_prefix(comma + 1);
  }
  return values;
}

absl::StatusOr<std::vector<TrueEffect>> ParseTrueEffect(std::string_view spec) {
  const size_t eq = spec.find('=');
  if (eq == std::string_view::npos) {
    return absl::InvalidArgumentError("--effect " + std::string(spec) + ": expected NAME=VALUE");
  }
  auto terms = ParseEffectSelector(spec.substr(0, eq));
  if (!terms.ok()) return terms.status();
  // A fault's onset follows its value: gyro_bias_step.x=3e-6@1500.
  const std::string_view value_text = spec.substr(eq + 1, spec.find('@', eq) - eq - 1);
  auto onset = ParseOnset(spec.substr(eq));
  if (!onset.ok()) return onset.status();
  if (terms->front().family->kind == EffectKind::kFault && !onset->has_value()) {
    return absl::InvalidArgumentError("--effect " + std::string(spec) + ": a fault takes its onset, NAME=VALUE@SECONDS");
  }
  if (terms->front().family->kind != EffectKind::kFault && onset->has_value()) {
    return absl::InvalidArgumentError("--effect " + std::string(spec) + ": only faults take an onset '@SECONDS'");
  }
  auto values = ParseNumberList(value_text, "--effect " + std::string(spec));
  if (!values.ok()) return values.status();
  const EffectFamily& family = *terms->front().family;
  const auto& v = *values;
  auto count_error = [&](const char* expected) {
    return absl::InvalidArgumentError("--effect " + std::string(spec) + ": " + std::string(family.name) +
                                      " takes " + expected);
  };
  std::vector<TrueEffect> effects;
  for (const EffectTerm& term : *terms) {
    TrueEffect e;
    e.term = term;
    e.onset_s = onset->value_or(0.0);
    switch (family.process) {
      case RandomProcess::kNone:
        if (v.empty() || v.size() > static_cast<size_t>(family.parameters_per_term)) {
          return count_error(family.parameters_per_term == 2 ? "VALUE or SIN,COS" : "one VALUE");
        }
        e.value[0] = v[0];
        if (v.size() > 1) e.value[1] = v[1];
        break;
      case RandomProcess::kRandomWalk:
        if (v.size() != 1 || v[0] < 0.0) return count_error("one non-negative density K");
        e.random_walk_density = v[0];
        break;
      case RandomProcess::kSecondOrderMarkov:
        if (v.size() != 3 || v[0] < 0.0 || v[1] <= 0.0 || v[2] <= 0.0) {
          return count_error("SIGMA,TAU_S,PERIOD_S (positive)");
        }
        e.second_order_sigma = v[0];
        e.second_order_alpha_per_s = 1.0 / v[1];
        e.second_order_beta_rad_s = 2.0 * std::numbers::pi / v[2];
        break;
      case RandomProcess::kDecayFromStart:
        if (v.size() != 2 || v[1] <= 0.0) return count_error("START,TAU_S (a positive time constant)");
        e.value[0] = v[0];
        e.time_constant_s = v[1];
        break;
    }
    effects.push_back(e);
  }
  return effects;
}

Datasheet DatasheetOf(const SensorTriadModel& gyro, const SensorTriadModel& acc) {
  Datasheet d;
  d.gyro_arw_rad_rts = AxisMean(gyro.white_noise_density);
  d.gyro_bias_sigma_rad_s = AxisRms(gyro.bias, &GaussMarkov::sigma);
  d.gyro_bias_tau_s = (gyro.bias[0].tau_s + gyro.bias[1].tau_s + gyro.bias[2].tau_s) / 3.0;
  d.acc_vrw_mps_rts = AxisMean(acc.white_noise_density);
  d.acc_bias_sigma_mps2 = AxisRms(acc.bias, &GaussMarkov::sigma);
  d.acc_bias_tau_s = (acc.bias[0].tau_s + acc.bias[1].tau_s + acc.bias[2].tau_s) / 3.0;
  return d;
}

namespace {

absl::Status CheckDrifts(const SimulatedUnit& unit) {
  for (const auto* triad : {&unit.gyro, &unit.acc}) {
    for (const auto& b : triad->bias) {
      if (b.sigma > 0.0 && !(b.tau_s > 0.0)) {
        return absl::InvalidArgumentError("a Gauss–Markov drift with σ > 0 needs a positive τ");
      }
    }
  }
  return absl::OkStatus();
}

// The random effects' processes at the first sample, and how many columns
// their states take in SimulatedRun::random_effect_states.
std::vector<RandomEffectState> InitialRandomEffects(const SimulatedUnit& unit, std::mt19937_64& rng,
                                                    std::normal_distribution<double>& normal,
                                                    int& columns) {
  std::vector<RandomEffectState> states;
  columns = 0;
  for (const TrueEffect& e : unit.effects) {
    if (e.term.family->process == RandomProcess::kNone) continue;
    RandomEffectState s{&e};
    if (e.term.family->process == RandomProcess::kSecondOrderMarkov) {
      s.x = e.second_order_sigma * Eigen::Vector2d(normal(rng), normal(rng));
      columns += 2;
    } else if (e.term.family->process == RandomProcess::kDecayFromStart) {
      s.x[0] = e.value[0];  // a warm-up is at its start value at the first sample
      columns += 1;
    } else {
      columns += 1;  // a rate random walk starts at zero at the first sample
    }
    states.push_back(s);
  }
  return states;
}

void WriteMetadata(const SimulatedUnit& unit, const TableProfile& profile,
                   const SimulationOptions& options, BenchRunMetadata& metadata) {
  metadata.format = "insdiag-bench-run/1";
  metadata.unit_serial = unit.serial;
  metadata.unit_type = unit.type;
  metadata.site = options.site;
  metadata.extra = {{"bench", "simulated two-axis rotary table"},
                    {"notes", "insdiag simulate: profile " + profile.name + ", seed " +
                                  std::to_string(options.seed)}};
  if (options.write_datasheet) {
    metadata.datasheet =
        options.datasheet.has_value() ? *options.datasheet : DatasheetOf(unit.gyro, unit.acc);
  }
}

// The deterministic and random sensor errors of sample k over [t0, t1]: the
// constant effects and faults, the random effects' states, the test unit's
// bias steps and spikes. A sample sees every drift as it stands at the start
// of its interval (the error model's convention); the caller adds the base
// drifts.
void AddEffectErrors(const SimulatedUnit& unit, const std::vector<RandomEffectState>& random_states,
                     size_t k, double t0, double t1, const RegressorInputs& sample_inputs,
                     Eigen::Vector3d& gyro_error, Eigen::Vector3d& acc_error,
                     Eigen::MatrixXd& random_effect_states) {
  RegressorInputs inputs = sample_inputs;
  for (const TrueEffect& e : unit.effects) {
    if (e.term.family->process != RandomProcess::kNone) continue;
    // A fault's regressor at the sample's middle: its mean over the sample
    // once the onset is past (a step within the sample counts from its middle).
    inputs.time_since_onset_s = 0.5 * (t0 + t1) - e.onset_s;
    const Eigen::Vector3d err = ConstantEffectError(e.term, inputs, e.value);
    (e.term.family->sensor == Sensor::kGyro ? gyro_error : acc_error) += err;
  }
  int column = 0;
  for (const RandomEffectState& s : random_states) {
    const TrueEffect& e = *s.effect;
    random_effect_states(static_cast<Eigen::Index>(k), column++) = s.x[0];
    if (e.term.family->process == RandomProcess::kSecondOrderMarkov) {
      random_effect_states(static_cast<Eigen::Index>(k), column++) = s.x[1];
    }
    (e.term.family->sensor == Sensor::kGyro ? gyro_error : acc_error)[e.term.axis] += s.x[0];
  }
  for (const BiasStep& step : unit.bias_steps) {
    if (t1 > step.time_s)
      (step.sensor == Sensor::kGyro ? gyro_error : acc_error)[step.axis] += step.size;
  }
  for (const Spike& spike : unit.spikes) {
    if (spike.time_s > t0 && spike.time_s <= t1) {
      (spike.sensor == Sensor::kGyro ? gyro_error : acc_error)[spike.axis] += spike.size;
    }
  }
}

}  // namespace

absl::StatusOr<SimulatedRun> Simulate(const SimulatedUnit& unit, const TableProfile& profile,
                                      const SimulationOptions& options) {
  if (!(options.sample_rate_hz > 0.0))
    return absl::InvalidArgumentError("the sample rate must be positive");
  auto motion_or = TableMotion::Compile(profile);
  if (!motion_or.ok()) return motion_or.status();
  const TableMotion& motion = *motion_or;
  if (absl::Status drifts = CheckDrifts(unit); !drifts.ok()) return drifts;

  const double dt = 1.0 / options.sample_rate_hz;
  const auto n = static_cast<size_t>(std::floor(motion.DurationS() * options.sample_rate_hz + 1e-9));
  const Eigen::Vector3d w_ie_n = wgs84::EarthRateNed(options.site.latitude_rad);
  const Eigen::Vector3d g_n = nav::GravityNed(options.site.latitude_rad, options.site.height_m);
  const std::vector<double> breakpoints = motion.Breakpoints();
  const bool perfect = options.perfect_sensors;

  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> normal(0.0, 1.0);

  // Base drifts start from their stationary distribution.
  Eigen::Vector3d gyro_gm, acc_gm;
  for (int i = 0; i < 3; ++i) {
    gyro_gm[i] = perfect ? 0.0 : unit.gyro.bias[i].sigma * normal(rng);
    acc_gm[i] = perfect ? 0.0 : unit.acc.bias[i].sigma * normal(rng);
  }
  int random_columns = 0;
  std::vector<RandomEffectState> random_states =
      InitialRandomEffects(unit, rng, normal, random_columns);

  SimulatedRun out;
  BenchRun& run = out.run;
  WriteMetadata(unit, profile, options, run.metadata);
  run.has_temperature = true;
  run.samples.resize(n);
  out.truth.resize(n);
  out.random_effect_states.resize(static_cast<Eigen::Index>(n), random_columns);

  Quantizer gyro_quantizer(perfect ? Eigen::Vector3d::Zero() : unit.gyro.quantization);
  Quantizer acc_quantizer(perfect ? Eigen::Vector3d::Zero() : unit.acc.quantization);
  const double temperature0 = profile.thermal.TemperatureAt(dt);
  size_t next_breakpoint = 0;

  for (size_t k = 0; k < n; ++k) {
    const double t0 = static_cast<double>(k) * dt;
    const double t1 = static_cast<double>(k + 1) * dt;
    IntervalIntegrals integrals;
    double a = t0;
    while (next_breakpoint < breakpoints.size() && breakpoints[next_breakpoint] <= a) ++next_breakpoint;
    while (next_breakpoint < breakpoints.size() && breakpoints[next_breakpoint] < t1) {
      AccumulateGaussLegendre(motion, w_ie_n, g_n, a, breakpoints[next_breakpoint], integrals);
      a = breakpoints[next_breakpoint++];
    }
    AccumulateGaussLegendre(motion, w_ie_n, g_n, a, t1, integrals);

    ImuSample& sample = run.samples[k];
    sample.t_s = t1;
    sample.ref_rpy_rad = nav::DcmToEuler(motion.BodyToNed(t1));
    sample.temp_degc = profile.thermal.TemperatureAt(t1);
    const Eigen::Vector3d true_rate = integrals.angle_rad / dt;
    const Eigen::Vector3d true_force = integrals.velocity_mps / dt;
    if (perfect) {
      sample.gyro_rad_s = true_rate;
      sample.acc_mps2 = true_force;
      continue;
    }

    Eigen::Vector3d gyro_error = gyro_gm;
    Eigen::Vector3d acc_error = acc_gm;
    RegressorInputs inputs;
    inputs.gyro_rad_s = true_rate;
    inputs.acc_mps2 = true_force;
    inputs.temperature_delta_degc = sample.temp_degc - temperature0;
    inputs.yaw_rad = std::atan2(integrals.sin_yaw_s, integrals.cos_yaw_s);
    AddEffectErrors(unit, random_states, k, t0, t1, inputs, gyro_error, acc_error,
                    out.random_effect_states);

    SampleTruth& truth = out.truth[k];
    truth.gyro_gm = gyro_gm;
    truth.acc_gm = acc_gm;
    truth.gyro_error = gyro_error;
    truth.acc_error = acc_error;
    // The drifts then advance over the interval.
    AdvanceDrifts(unit, dt, gyro_gm, acc_gm, random_states, rng, normal);

    Eigen::Vector3d gyro_noise, acc_noise;
    for (int i = 0; i < 3; ++i) {
      gyro_noise[i] = unit.gyro.white_noise_density[i] / std::sqrt(dt) * normal(rng);
      acc_noise[i] = unit.acc.white_noise_density[i] / std::sqrt(dt) * normal(rng);
    }
    sample.gyro_rad_s = gyro_quantizer.Apply(true_rate + gyro_error + gyro_noise, dt);
    sample.acc_mps2 = acc_quantizer.Apply(true_force + acc_error + acc_noise, dt);
  }
  return out;
}

}  // namespace insdiag::engine::sim
