#include "insdiag/engine/ident/allan.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <numeric>
#include <optional>
#include <string>
#include <utility>

#include "ident/allan_model.h"
#include "insdiag/engine/ident/count_quantum.h"
#include "insdiag/engine/model/drift_axis.h"
#include "insdiag/engine/model/flicker_floor.h"
#include "insdiag/engine/model/parameters.h"
#include "insdiag/engine/monitor/sample_screening.h"
#include "insdiag/engine/nav/rotation.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine::ident {
namespace {

using namespace allan_model;  // the curve's model, shared with the fit and the covariance

// χ²_ν quantile. The engine's bisection is exact but needs O(√ν) terms per
// evaluation; above ν = 200 the Wilson–Hilferty cube (relative error < 1e-4
// there) is as good for a confidence interval and costs nothing.
double ChiSquareQuantileFast(double p, double dof) {
  if (dof <= 200.0) return stats::ChiSquareQuantile(p, dof);
  const double z = stats::NormalQuantile(p);
  const double c = 2.0 / (9.0 * dof);
  const double w = 1.0 - c + z * std::sqrt(c);
  return dof * w * w * w;
}

// ---------------------------------------------------------------------------
// Curve.

// Least-squares slope of ln σ̂ against ln τ within ± `window` decades of each point.
std::vector<double> LocalSlopes(const std::vector<AllanPoint>& curve, double window) {
  std::vector<double> slope(curve.size(), -0.5);
  for (size_t j = 0; j < curve.size(); ++j) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    int n = 0;
    for (const AllanPoint& p : curve) {
      if (!(p.adev > 0.0) || std::abs(std::log10(p.tau_s / curve[j].tau_s)) > window + 1e-12) continue;
      const double x = std::log(p.tau_s);
      const double y = std::log(p.adev);
      sx += x;
      sy += y;
      sxx += x * x;
      sxy += x * y;
      ++n;
    }
    const double den = n * sxx - sx * sx;
    if (n >= 2 && den > 0.0) slope[j] = (n * sxy - sx * sy) / den;
  }
  return slope;
}

PowerLawNoise NoiseFromSlope(double mu) {
  if (mu < -0.75) return PowerLawNoise::kWhitePhase;  // phase noise: see AllanEdf's caller
  if (mu < -0.25) return PowerLawNoise::kWhiteRate;
  if (mu < 0.25) return PowerLawNoise::kFlickerRate;
  return PowerLawNoise::kRandomWalkRate;
}

// Angle of the rotation between two attitudes, for the stillness test.
class AttitudeTest {
 public:
  explicit AttitudeTest(double tolerance_rad) : tolerance_rad_(tolerance_rad) {}
  void SetAnchor(const Eigen::Vector3d& rpy) {
    anchor_rpy_ = rpy;
    anchor_ready_ = false;
  }
  bool Within(const Eigen::Vector3d& rpy) {
    if (rpy == anchor_rpy_) return true;
    if (!anchor_ready_) {
      C_anchor_t_ = nav::EulerToDcm(anchor_rpy_).transpose();
      anchor_ready_ = true;
    }
    const Eigen::Matrix3d R = C_anchor_t_ * nav::EulerToDcm(rpy);
    if (R.trace() < 1.0) return false;  // more than 90°
    const Eigen::Vector3d v(R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1));
    return std::asin(std::min(1.0, 0.5 * v.norm())) <= tolerance_rad_;
  }

 private:
  double tolerance_rad_;
  Eigen::Vector3d anchor_rpy_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d C_anchor_t_ = Eigen::Matrix3d::Identity();
  bool anchor_ready_ = false;
};

// Still spans before the guard and the length rule.
std::vector<StaticSegment> StillSpans(const BenchRun& run, double tau0, const AllanOptions& options) {
  std::vector<StaticSegment> spans;
  const auto& s = run.samples;
  AttitudeTest test(options.attitude_tolerance_rad);
  size_t start = 0;
  test.SetAnchor(s[0].ref_rpy_rad);
  auto close = [&](size_t end) {
    if (end > start) spans.push_back({start, end, 0.0, 0.0});
  };
  for (size_t k = 1; k < s.size(); ++k) {
    const bool gap = s[k].t_s - s[k - 1].t_s > options.gap_factor * tau0;
    if (!gap && test.Within(s[k].ref_rpy_rad)) continue;
    // Sample k moved (or follows a gap): the next hold starts with sample k + 1,
    // whose interval begins at epoch k.
    close(k);
    start = k + 1;
    test.SetAnchor(s[k].ref_rpy_rad);
  }
  close(s.size());
  return spans;
}

}  // namespace

// ---------------------------------------------------------------------------

size_t AllanOptions::MinSegmentSamples(double tau0_s) const {
  return static_cast<size_t>(std::ceil(min_segment_s / tau0_s - 1e-6));
}

absl::Status AllanOptions::Validate() const {
  if (!(attitude_tolerance_rad > 0.0)) return absl::InvalidArgumentError("Allan: the attitude tolerance must be positive");
  if (!(min_segment_s > 0.0)) return absl::InvalidArgumentError("Allan: the minimum segment length must be positive");
  if (!(motion_guard_s >= 0.0)) return absl::InvalidArgumentError("Allan: the motion guard must be non-negative");
  if (!(gap_factor > 1.0)) return absl::InvalidArgumentError("Allan: the gap factor must exceed 1");
  if (points_per_decade < 1 || points_per_decade > 100) {
    return absl::InvalidArgumentError("Allan: points per decade must be in [1, 100]");
  }
  if (!(max_cluster_fraction > 0.0 && max_cluster_fraction <= 0.5)) {
    return absl::InvalidArgumentError("Allan: the largest cluster fraction must be in (0, 0.5]");
  }
  if (!(confidence > 0.0 && confidence < 1.0)) return absl::InvalidArgumentError("Allan: confidence must be in (0, 1)");
  if (!(slope_window_decades > 0.0)) return absl::InvalidArgumentError("Allan: the slope window must be positive");
  if (!(significance_z >= 0.0)) return absl::InvalidArgumentError("Allan: the significance z must be non-negative");
  if (!(adequacy_alpha > 0.0 && adequacy_alpha < 1.0)) {
    return absl::InvalidArgumentError("Allan: the adequacy level must be in (0, 1)");
  }
  if (!(jump_alpha >= 0.0 && jump_alpha < 1.0))
    return absl::InvalidArgumentError("Allan: the jump level must be in [0, 1)");
  if (jump_min_windows < 8)
    return absl::InvalidArgumentError("Allan: the jump test needs at least 8 windows");
  if (max_solver_iterations < 1) return absl::InvalidArgumentError("Allan: the solver needs at least one iteration");
  return absl::OkStatus();
}

double AllanEdf(PowerLawNoise noise, int64_t phase_points, int64_t m) {
  const auto N = static_cast<double>(phase_points);
  const auto dm = static_cast<double>(m);
  const double M = N - 2.0 * dm;
  if (M < 1.0 || m < 1) return 0.0;
  double edf = 1.0;
  switch (noise) {
    case PowerLawNoise::kWhitePhase:
      edf = (N + 1.0) * (N - 2.0 * dm) / (2.0 * (N - dm));
      break;
    case PowerLawNoise::kFlickerPhase: {
      const double a = std::log((N - 1.0) / (2.0 * dm));
      const double b = std::log((2.0 * dm + 1.0) * (N - 1.0) / 4.0);
      edf = a > 0.0 && b > 0.0 ? std::exp(std::sqrt(a * b)) : 1.0;
      break;
    }
    case PowerLawNoise::kWhiteRate:
      edf = (3.0 * (N - 1.0) / (2.0 * dm) - 2.0 * (N - 2.0) / N) * 4.0 * dm * dm / (4.0 * dm * dm + 5.0);
      break;
    case PowerLawNoise::kFlickerRate:
      edf = m == 1 ? 2.0 * (N - 2.0) * (N - 2.0) / (2.3 * N - 4.9) : 5.0 * N * N / (4.0 * dm * (N + 3.0 * dm));
      break;
    case PowerLawNoise::kRandomWalkRate:
      edf = N > 3.0 ? (N - 2.0) / (dm * (N - 3.0) * (N - 3.0)) *
                          ((N - 1.0) * (N - 1.0) - 3.0 * dm * (N - 1.0) + 4.0 * dm * dm)
                    : 1.0;
      break;
  }
  return std::clamp(edf, 1.0, M);
}

double ModelAllanVariance(const AllanNoiseTerms& t, double tau_s) {
  double s = 3.0 * t.quantization * t.quantization / (tau_s * tau_s) + t.white_density * t.white_density / tau_s +
             kFlickerAvar * t.bias_instability * t.bias_instability +
             t.rate_random_walk * t.rate_random_walk * tau_s / 3.0 + 0.5 * t.rate_ramp * t.rate_ramp * tau_s * tau_s;
  if (t.markov_sigma > 0.0 && t.markov_tau_s > 0.0) {
    s += t.markov_sigma * t.markov_sigma * MarkovShape(tau_s / t.markov_tau_s);
  }
  return s;
}

const char* AllanParameterName(AllanParameter p) {
  static constexpr const char* kNames[kP] = {"Q", "N", "B", "K", "R", "markov_sigma", "markov_tau"};
  return kNames[static_cast<int>(p)];
}

AllanNoiseTerms AllanFit::Terms() const {
  auto v = [&](AllanParameter p) { return (*this)[p].included ? (*this)[p].value : 0.0; };
  AllanNoiseTerms t;
  t.quantization = v(AllanParameter::kQuantization);
  t.white_density = v(AllanParameter::kWhiteDensity);
  t.bias_instability = v(AllanParameter::kBiasInstability);
  t.rate_random_walk = v(AllanParameter::kRateRandomWalk);
  t.rate_ramp = v(AllanParameter::kRateRamp);
  t.markov_sigma = v(AllanParameter::kMarkovSigma);
  t.markov_tau_s = v(AllanParameter::kMarkovTau);
  return t;
}

absl::StatusOr<std::vector<StaticSegment>> FindStaticSegments(const BenchRun& run, const AllanOptions& options) {
  if (auto st = options.Validate(); !st.ok()) return st;
  if (run.samples.size() < 2) return absl::InvalidArgumentError("Allan: the run has fewer than two samples");
  const double tau0 = run.NominalIntervalS();
  if (!(tau0 > 0.0)) return absl::InvalidArgumentError("Allan: the run has no positive sample interval");
  const auto guard = static_cast<size_t>(std::ceil(options.motion_guard_s / tau0 - 1e-9));
  const size_t min_samples = options.MinSegmentSamples(tau0);
  const size_t n = run.samples.size();
  std::vector<StaticSegment> out;
  for (StaticSegment s : StillSpans(run, tau0, options)) {
    if (s.first_sample > 0) s.first_sample += guard;
    if (s.end_sample < n) s.end_sample = s.end_sample > guard ? s.end_sample - guard : 0;
    if (s.end_sample <= s.first_sample || s.Samples() < min_samples) continue;
    s.start_s = run.samples[s.first_sample].t_s - tau0;
    s.end_s = run.samples[s.end_sample - 1].t_s;
    out.push_back(s);
  }
  return out;
}

void allan_model::PhaseOfRates(std::span<const double> y, std::vector<double>& th) {
  // Compensated (Neumaier) sums, so that second differences keep full
  // precision however far θ wanders.
  double mean = 0.0;
  double mean_c = 0.0;
  for (double v : y) {
    const double t = mean + v;
    mean_c += std::abs(mean) >= std::abs(v) ? (mean - t) + v : (v - t) + mean;
    mean = t;
  }
  mean = (mean + mean_c) / static_cast<double>(y.size());
  th.assign(y.size() + 1, 0.0);
  double sum = 0.0;
  double comp = 0.0;
  for (size_t k = 0; k < y.size(); ++k) {
    const double v = y[k] - mean;
    const double t = sum + v;
    comp += std::abs(sum) >= std::abs(v) ? (sum - t) + v : (v - t) + sum;
    sum = t;
    th[k + 1] = sum + comp;
  }
}

std::vector<double> allan_model::PhaseOfRates(std::span<const double> y) {
  std::vector<double> th;
  PhaseOfRates(y, th);
  return th;
}

std::vector<int64_t> AllanClusterSizes(size_t longest_samples, const AllanOptions& options) {
  const auto m_max = static_cast<int64_t>(std::floor(options.max_cluster_fraction * static_cast<double>(longest_samples)));
  std::vector<int64_t> m;
  for (int k = 0;; ++k) {
    const auto mk = static_cast<int64_t>(std::llround(std::pow(10.0, static_cast<double>(k) / options.points_per_decade)));
    if (mk > m_max) break;
    if (m.empty() || mk > m.back()) m.push_back(mk);
  }
  return m;
}

std::vector<AllanPoint> OverlappingAllanCurve(std::span<const std::vector<double>> segment_rates, double tau0_s,
                                              std::span<const int64_t> cluster_sizes, const AllanOptions& options) {
  std::vector<std::vector<double>> theta;
  theta.reserve(segment_rates.size());
  for (const std::vector<double>& y : segment_rates) theta.push_back(PhaseOfRates(y));

  std::vector<AllanPoint> curve;
  for (int64_t m : cluster_sizes) {
    double sum = 0.0;
    int64_t count = 0;
    for (const std::vector<double>& th : theta) {
      const int64_t M = static_cast<int64_t>(th.size()) - 2 * m;
      if (M < 1) continue;
      const double* x0 = th.data();
      const double* x1 = x0 + m;
      const double* x2 = x0 + 2 * m;
      double acc[4] = {0.0, 0.0, 0.0, 0.0};
      int64_t k = 0;
      for (; k + 4 <= M; k += 4) {
        for (int l = 0; l < 4; ++l) {
          const double d = x2[k + l] - 2.0 * x1[k + l] + x0[k + l];
          acc[l] += d * d;
        }
      }
      for (; k < M; ++k) {
        const double d = x2[k] - 2.0 * x1[k] + x0[k];
        acc[0] += d * d;
      }
      sum += (acc[0] + acc[1]) + (acc[2] + acc[3]);
      count += M;
    }
    if (count < 1) continue;
    AllanPoint p;
    p.m = m;
    p.tau_s = tau0_s * static_cast<double>(m);
    p.differences = count;
    const double md = static_cast<double>(m);
    p.adev = std::sqrt(sum / (2.0 * md * md * static_cast<double>(count)));
    curve.push_back(p);
  }

  // Noise type from the local slope, ν summed over segments, χ² interval.
  const std::vector<double> slope = LocalSlopes(curve, options.slope_window_decades);
  for (size_t j = 0; j < curve.size(); ++j) {
    AllanPoint& p = curve[j];
    p.noise = NoiseFromSlope(slope[j]);
    double edf = 0.0;
    double edf_flicker_phase = 0.0;
    for (const std::vector<double>& th : theta) {
      const auto N = static_cast<int64_t>(th.size());
      edf += AllanEdf(p.noise, N, p.m);
      p.edf_reddest += AllanEdf(PowerLawNoise::kRandomWalkRate, N, p.m);
      if (p.noise == PowerLawNoise::kWhitePhase) edf_flicker_phase += AllanEdf(PowerLawNoise::kFlickerPhase, N, p.m);
    }
    // Slope −1: white or flicker phase noise; take the smaller ν.
    if (p.noise == PowerLawNoise::kWhitePhase && edf_flicker_phase < edf) {
      edf = edf_flicker_phase;
      p.noise = PowerLawNoise::kFlickerPhase;
    }
    p.edf = edf;
    const double hi_q = ChiSquareQuantileFast(0.5 * (1.0 + options.confidence), edf);
    const double lo_q = ChiSquareQuantileFast(0.5 * (1.0 - options.confidence), edf);
    p.ci_low = p.adev * std::sqrt(edf / hi_q);
    p.ci_high = lo_q > 0.0 ? p.adev * std::sqrt(edf / lo_q) : std::numeric_limits<double>::infinity();
  }
  return curve;
}

namespace {

// One channel's rates in the static segments, cut at their jumps (each
// piece at least min_segment_s long, as the jump test needs that much on
// either side of a cut).
std::vector<std::vector<double>> PiecesBetweenJumps(
    const BenchRun& run, const std::vector<StaticSegment>& segments, int channel, double tau0,
    const AllanOptions& options, std::vector<RateJump>& jumps, std::vector<size_t>& first_samples) {
  std::vector<std::vector<double>> out;
  std::vector<double> rates;
  for (const StaticSegment& seg : segments) {
    rates.resize(seg.Samples());
    for (size_t k = 0; k < seg.Samples(); ++k) {
      rates[k] = SensorChannelValue(run.samples[seg.first_sample + k], channel);
    }
    std::vector<RateJump> in_segment;
    for (const RatePiece& piece : CutAtRateJumps(rates, tau0, options, &in_segment)) {
      out.emplace_back(rates.begin() + static_cast<std::ptrdiff_t>(piece.begin),
                       rates.begin() + static_cast<std::ptrdiff_t>(piece.end));
      first_samples.push_back(seg.first_sample + piece.begin);
    }
    for (RateJump& j : in_segment) {
      j.time_s = run.samples[seg.first_sample + j.sample - 1].t_s;
      jumps.push_back(j);
    }
  }
  return out;
}

// Each piece less its least-squares ramp (allan.h: Ramps); the ramp that
// removed the most, its onset as a time in the run.
std::vector<RateRamp> TakeOutRamps(const BenchRun& run, std::vector<std::vector<double>>& pieces,
                                   const std::vector<size_t>& first_samples, double tau0,
                                   const AllanOptions& options) {
  std::optional<RateRamp> largest;
  for (size_t i = 0; i < pieces.size(); ++i) {
    std::vector<double>& y = pieces[i];
    std::optional<RateRamp> ramp = FitRateRamp(y, tau0, options.MinSegmentSamples(tau0));
    if (!ramp.has_value()) continue;
    const double per_sample = ramp->slope * tau0;
    for (size_t k = ramp->onset_sample + 1; k < y.size(); ++k)
      y[k] -= per_sample * static_cast<double>(k - ramp->onset_sample);
    ramp->onset_s = run.samples[first_samples[i] + ramp->onset_sample].t_s;
    if (!largest.has_value() || ramp->residual_reduction > largest->residual_reduction)
      largest = ramp;
  }
  return largest.has_value() ? std::vector<RateRamp>{*largest} : std::vector<RateRamp>{};
}

}  // namespace

double AllanChannel::CountedQuantisation() const {
  return count_quantum.has_value() ? *count_quantum / std::sqrt(12.0) : 0.0;
}

double AllanChannel::Quantisation() const {
  const AllanTermEstimate& q = fit[AllanParameter::kQuantization];
  return std::max(CountedQuantisation(), q.included ? q.value : 0.0);
}

bool AllanChannel::QuantisationIsCounted() const {
  const AllanTermEstimate& q = fit[AllanParameter::kQuantization];
  return count_quantum.has_value() && !(q.included && q.value > CountedQuantisation());
}

absl::StatusOr<AllanResult> AllanAnalysis(const BenchRun& run, const AllanOptions& options) {
  auto segments = FindStaticSegments(run, options);
  if (!segments.ok()) return segments.status();
  const double tau0 = run.NominalIntervalS();
  if (segments->empty()) {
    double longest = 0.0;
    for (const StaticSegment& s : StillSpans(run, tau0, options)) longest = std::max(longest, s.Samples() * tau0);
    return absl::FailedPreconditionError(
        "Allan: no static segment of at least " + FormatG(options.min_segment_s) + " s (the longest still span is " +
        FormatG(longest) + " s with an attitude tolerance of " + FormatG(options.attitude_tolerance_rad) + " rad)");
  }
  AllanResult result;
  result.tau0_s = tau0;
  const auto count_quanta = CountQuanta(run);
  result.segments = *std::move(segments);
  for (const StaticSegment& s : result.segments) result.samples_used += s.Samples();
  for (int c = 0; c < 6; ++c) {
    AllanChannel ch;
    ch.name = std::string(kSensorChannelNames[c]);
    ch.sensor = c < 3 ? Sensor::kGyro : Sensor::kAccelerometer;
    ch.axis = c % 3;
    ch.unit = std::string(UnitsOf(ch.sensor).rate);
    std::vector<size_t> first_samples;
    std::vector<std::vector<double>> pieces =
        PiecesBetweenJumps(run, result.segments, c, tau0, options, ch.jumps, first_samples);
    std::vector<size_t> lengths;
    size_t longest = 0;
    for (const std::vector<double>& piece : pieces) {
      lengths.push_back(piece.size());
      longest = std::max(longest, piece.size());
    }
    const std::vector<int64_t> m = AllanClusterSizes(longest, options);
    if (m.empty())
      return absl::FailedPreconditionError(
          "Allan: the static segments are too short for any cluster");
    ch.curve = OverlappingAllanCurve(pieces, tau0, m, options);
    ch.count_quantum = count_quanta[static_cast<size_t>(DriftAxis{ch.sensor, ch.axis}.Index())];
    ch.ramp_evidence = RampBeyondNoise(pieces, ch.curve, options);
    if (ch.ramp_evidence.has_value()) {
      ch.ramps = TakeOutRamps(run, pieces, first_samples, tau0, options);
      ch.curve = OverlappingAllanCurve(pieces, tau0, m, options);
    }
    auto fit = FitAllanCurve(ch.curve, tau0, lengths, options);
    if (fit.ok()) {
      ch.fit = *std::move(fit);
    } else {
      ch.fit.notes.push_back(std::string(fit.status().message()));
    }
    result.channels.push_back(std::move(ch));
  }
  return result;
}

std::vector<ParameterEstimate> AllanParameterEstimates(const AllanResult& result, const ErrorModel* a_priori) {
  std::map<std::string, double> prior;
  if (a_priori != nullptr) {
    for (const NamedParameter& p : ParametersOf(*a_priori)) prior[p.name] = p.value;
  }
  static constexpr const char* kAxis[3] = {"x", "y", "z"};
  std::vector<ParameterEstimate> out;
  for (const AllanChannel& ch : result.channels) {
    const bool gyro = ch.sensor == Sensor::kGyro;
    const std::string s = gyro ? "gyro" : "acc";
    const std::string axis = kAxis[ch.axis];
    auto push = [&](const std::string& name, std::string_view unit, double value, double std_error) {
      ParameterEstimate e;
      e.name = name;
      e.value = value;
      e.std_error = std_error;
      e.method = EstimationMethod::kAllan;
      e.unit = std::string(unit);
      if (auto it = prior.find(name); it != prior.end()) e.a_priori = it->second;
      out.push_back(e);
    };
    auto add = [&](AllanParameter p, const std::string& name, std::string_view unit) {
      const AllanTermEstimate& t = ch.fit[p];
      if (t.included) push(name, unit, t.value, t.std_error);
    };
    const DriftAxis drift{ch.sensor, ch.axis};
    const SensorUnits units = UnitsOf(ch.sensor);
    if (ch.QuantisationIsCounted()) {
      // Read from the samples' lattice, not estimated: no standard error.
      push(QuantizationName(drift), units.quantization, ch.Quantisation(), 0.0);
    } else {
      add(AllanParameter::kQuantization, QuantizationName(drift), units.quantization);
    }
    add(AllanParameter::kWhiteDensity, WhiteNoiseName(drift), units.white_density);
    add(AllanParameter::kBiasInstability, s + "_bias_instability." + axis, units.rate);
    add(AllanParameter::kRateRandomWalk, s + "_rate_random_walk." + axis, units.rate_walk);
    add(AllanParameter::kRateRamp, s + "_rate_ramp." + axis, units.rate_ramp);
    add(AllanParameter::kMarkovSigma, DriftSigmaName(drift), units.rate);
    add(AllanParameter::kMarkovTau, DriftTauName(drift), "s");
  }
  return out;
}

namespace {

// A drift read from a channel's Allan fit, and how it was read (the note).
struct DriftPlaceholderRead {
  GaussMarkov drift;
  std::string how;
};

// The drift of the fitted Markov term, if the fit has one.
std::optional<DriftPlaceholderRead> MarkovDrift(const AllanChannel& ch) {
  if (!ch.fit[AllanParameter::kMarkovSigma].included) return std::nullopt;
  const AllanNoiseTerms terms = ch.fit.Terms();
  return DriftPlaceholderRead{GaussMarkov{terms.markov_sigma, terms.markov_tau_s},
                              "drift from the fitted Gauss–Markov term"};
}

// The curve still rising at its longest τ = T: a drift slower than the
// segments, τ set to T. Its σ² is 3/2 of the rising terms' Allan variance at
// T, K²T/3 + R²T²/2 (IEEE Std 952-1997, Table C.1) — for a rate random walk
// alone K²T/2, the walk's variance over T/2. A ramp counts: over segments
// shorter than the drift's τ, a drift's rise looks like one, and the walk's
// coefficient may then fit to nothing.
std::optional<DriftPlaceholderRead> RisingDrift(const AllanChannel& ch) {
  if (!ch.fit[AllanParameter::kRateRandomWalk].included && !ch.fit[AllanParameter::kRateRamp].included) {
    return std::nullopt;
  }
  const AllanNoiseTerms terms = ch.fit.Terms();
  const double T = ch.curve.back().tau_s;
  AllanNoiseTerms rising;
  rising.rate_random_walk = terms.rate_random_walk;
  rising.rate_ramp = terms.rate_ramp;
  return DriftPlaceholderRead{GaussMarkov{std::sqrt(1.5 * ModelAllanVariance(rising, T)), T},
                              "drift from the rate random walk and ramp with T = the longest τ analysed (" +
                                  FormatG(T) + " s)"};
}

// What a channel's drift carries beside a flicker floor the model carries:
// the Markov term, else the rising branch, else nothing.
std::optional<DriftPlaceholderRead> DriftBeyondTheFloor(const AllanChannel& ch) {
  if (auto markov = MarkovDrift(ch); markov.has_value()) return markov;
  return RisingDrift(ch);
}

// The Gauss–Markov drift a channel's Allan fit stands for where the model
// carries no floor, and how it was read: the fitted Markov term; else the
// larger of the drifts the flicker floor and the rising branch stand for
// (one process carries both, and the smaller is within its noise); else the
// bound from the curve's lowest point.
absl::StatusOr<DriftPlaceholderRead> DriftPlaceholder(const AllanChannel& ch) {
  const AllanFit& fit = ch.fit;
  const AllanNoiseTerms terms = fit.Terms();
  const MarkovPeak& peak = MarkovShapePeak();
  auto lowest = [&](bool fitted) {
    const AllanPoint* best = nullptr;
    for (const AllanPoint& p : ch.curve) {
      const double v = fitted ? p.fitted_adev : p.adev;
      if (!(v > 0.0)) continue;
      if (best == nullptr || v < (fitted ? best->fitted_adev : best->adev)) best = &p;
    }
    return best;
  };
  if (auto markov = MarkovDrift(ch); markov.has_value()) return *markov;
  std::optional<DriftPlaceholderRead> floor_drift;
  if (fit[AllanParameter::kBiasInstability].included) {
    const AllanPoint* p = lowest(true);
    const double floor = std::sqrt(kFlickerAvar) * terms.bias_instability;
    const double tau_floor = p != nullptr ? p->tau_s : ch.curve.back().tau_s;
    floor_drift = {GaussMarkov{floor / std::sqrt(peak.g), tau_floor / peak.u},
                   "drift from the bias instability: the Markov process whose Allan peak is the flicker floor at τ = " +
                       FormatG(tau_floor) + " s"};
  }
  const std::optional<DriftPlaceholderRead> rising_drift = RisingDrift(ch);
  if (floor_drift.has_value() && rising_drift.has_value()) {
    return rising_drift->drift.sigma > floor_drift->drift.sigma ? *rising_drift : *floor_drift;
  }
  if (floor_drift.has_value()) return *floor_drift;
  if (rising_drift.has_value()) return *rising_drift;
  const AllanPoint* p = lowest(false);
  if (p == nullptr) return absl::InvalidArgumentError("Allan: channel " + ch.name + " has no positive deviation");
  return DriftPlaceholderRead{GaussMarkov{p->adev / std::sqrt(peak.g), p->tau_s / peak.u},
                              "no drift term resolved; Gauss–Markov drift set to the bound from the curve's lowest point"};
}

}  // namespace

absl::StatusOr<ErrorModel> ErrorModelFromAllan(const AllanResult& result, const ReferenceAccuracy& reference,
                                               std::vector<std::string>* notes) {
  if (result.channels.size() != 6) return absl::InvalidArgumentError("Allan: the result does not hold six channels");
  ErrorModel model;
  model.reference = reference;
  auto note = [&](const std::string& s) {
    if (notes != nullptr) notes->push_back(s);
  };
  double longest_segment_s = 0.0;
  for (const StaticSegment& s : result.segments) longest_segment_s = std::max(longest_segment_s, s.end_s - s.start_s);
  for (const AllanChannel& ch : result.channels) {
    SensorTriadModel& triad = ch.sensor == Sensor::kGyro ? model.gyro : model.acc;
    const AllanFit& fit = ch.fit;
    const AllanNoiseTerms terms = fit.Terms();
    const auto axis = static_cast<size_t>(ch.axis);
    if (ch.curve.empty()) return absl::InvalidArgumentError("Allan: channel " + ch.name + " has no curve");

    // White noise: N, else the tangent bound min σ̂ √τ.
    if (fit[AllanParameter::kWhiteDensity].included) {
      triad.white_noise_density[ch.axis] = fit[AllanParameter::kWhiteDensity].value;
    } else {
      double bound = std::numeric_limits<double>::infinity();
      for (const AllanPoint& p : ch.curve) {
        if (p.adev > 0.0) bound = std::min(bound, p.adev * std::sqrt(p.tau_s));
      }
      triad.white_noise_density[ch.axis] = std::isfinite(bound) ? bound : 0.0;
      note(ch.name + ": white noise not resolved, density set to the bound min σ̂√τ");
    }
    triad.quantization[ch.axis] = ch.Quantisation();

    // A flicker floor the filter carries as a floor (model/flicker_floor.h),
    // over the cluster times where it stands above the white noise, up to
    // the longest still segment; the axis' drift then carries what the curve
    // shows beyond it: the Markov term, else the rising branch, else nothing.
    const FlickerFloor floor =
        fit[AllanParameter::kBiasInstability].included
            ? FlickerFloorAbove(terms.bias_instability, triad.white_noise_density[ch.axis], ch.curve.front().tau_s,
                                longest_segment_s)
            : FlickerFloor{};
    const std::vector<GaussMarkov> components = FlickerComponents(floor);
    if (!components.empty()) {
      triad.flicker[axis] = floor;
      std::string beyond = "nothing beyond it";
      triad.bias[axis] = GaussMarkov{0.0, components.front().tau_s};
      if (auto drift = DriftBeyondTheFloor(ch); drift.has_value()) {
        triad.bias[axis] = drift->drift;
        beyond = drift->how;
      }
      note(ch.name + ": bias instability " + FormatG(floor.coefficient) + " " + ch.unit + " over τ = " +
           FormatG(floor.shortest_tau_s) + "–" + FormatG(floor.longest_tau_s) + " s, carried as " +
           std::to_string(components.size()) + " Gauss–Markov states; " + beyond);
      continue;
    }
    auto drift = DriftPlaceholder(ch);
    if (!drift.ok()) return drift.status();
    triad.bias[axis] = drift->drift;
    note(ch.name + ": " + drift->how);
  }
  return model;
}

std::vector<AllanDeparture> AllanDeparturesFrom(const AllanResult& result, const ErrorModel& model,
                                                double family_wise_alpha) {
  size_t points = 0;
  for (const AllanChannel& ch : result.channels) points += ch.curve.size();
  // Each tail of every point's interval, Bonferroni over the curve's points.
  const double tail = 0.5 * family_wise_alpha / static_cast<double>(std::max<size_t>(1, points));
  std::vector<AllanDeparture> out;
  for (const AllanChannel& ch : result.channels) {
    const SensorTriadModel& triad = ch.sensor == Sensor::kGyro ? model.gyro : model.acc;
    const auto axis = static_cast<size_t>(ch.axis);
    AllanNoiseTerms predicted;
    predicted.quantization = triad.quantization[ch.axis];
    predicted.white_density = triad.white_noise_density[ch.axis];
    predicted.markov_sigma = triad.bias[axis].sigma;
    predicted.markov_tau_s = triad.bias[axis].tau_s;
    // A flicker floor's components beside the drift (model/flicker_floor.h).
    const std::vector<GaussMarkov> flicker = FlickerComponents(triad.flicker[axis]);
    AllanDeparture farthest{ch.name, 0.0, 1.0};
    for (const AllanPoint& p : ch.curve) {
      double model_avar = ModelAllanVariance(predicted, p.tau_s);
      for (size_t j = 0; j < flicker.size(); ++j) {
        model_avar += flicker[j].sigma * flicker[j].sigma * MarkovShape(p.tau_s / flicker[j].tau_s);
      }
      const double model_adev = std::sqrt(model_avar);
      if (!(model_adev > 0.0) || !(p.adev > 0.0) || !(p.edf > 0.0)) continue;
      // σ² ν/χ²_ν within its interval (the curve's own intervals, at the
      // family-wise level).
      const double low = p.adev * std::sqrt(p.edf / ChiSquareQuantileFast(1.0 - tail, p.edf));
      const double high = p.adev * std::sqrt(p.edf / ChiSquareQuantileFast(tail, p.edf));
      AllanDeparture here{ch.name, p.tau_s, 1.0};
      if (low > model_adev) here.ratio = low / model_adev;
      if (high < model_adev) here.ratio = high / model_adev;
      if (here.LogDistance() > farthest.LogDistance()) farthest = here;
    }
    out.push_back(farthest);
  }
  return out;
}

}  // namespace insdiag::engine::ident
