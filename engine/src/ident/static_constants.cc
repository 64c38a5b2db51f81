#include "insdiag/engine/ident/static_constants.h"

#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>

#include <algorithm>
#include <cmath>

#include "insdiag/engine/filter/epoch_run.h"
#include "insdiag/engine/nav/rotation.h"
#include "insdiag/engine/nav/wgs84.h"

namespace insdiag::engine::ident {
namespace {

// Variance of the time average over T of white noise of density N plus a
// first-order Gauss–Markov process (σ, τ) (see the header).
double MeanVariance(double white_density, const GaussMarkov& drift, double duration_s) {
  double variance = white_density * white_density / duration_s;
  if (drift.sigma > 0.0 && drift.tau_s > 0.0) {
    const double r = drift.tau_s / duration_s;
    variance += 2.0 * drift.sigma * drift.sigma * r * (1.0 - r * -std::expm1(-1.0 / r));
  }
  return variance;
}

}  // namespace

bool StaticConstants::AnyDominant() const {
  return std::any_of(axes.begin(), axes.end(), [](const StaticConstant& c) { return c.dominant; });
}

absl::StatusOr<StaticConstants> MeasureStaticConstants(const BenchRun& run,
                                                       const std::vector<StaticSegment>& segments,
                                                       const ErrorModel& a_priori,
                                                       const DominantConstantOptions& options, ConstantPrior prior) {
  const Site& site = run.metadata.site;
  const Eigen::Vector3d earth_rate_n = wgs84::EarthRateNed(site.latitude_rad);
  const Eigen::Vector3d specific_force_n(0.0, 0.0, -wgs84::NormalGravityMps2(site.latitude_rad, site.height_m));

  size_t count = 0;
  double static_s = 0.0;
  for (const StaticSegment& s : segments) {
    const size_t end = std::min(s.end_sample, run.samples.size());
    count += end > s.first_sample ? end - s.first_sample : 0;
    static_s += s.end_s - s.start_s;
  }
  if (count == 0 || !(static_s > 0.0)) {
    return absl::FailedPreconditionError("the run has no static segment to measure its constant biases on");
  }

  // Reading minus a perfect unit's, per static sample (gyro x, y, z, acc x,
  // y, z), summed whole and per batch. The standard error of each mean from
  // the data: the scatter of the means of equal consecutive batches (batch
  // means, Law & Kelton, Simulation Modeling and Analysis, 3rd ed., §9.5.3);
  // it stands in when the a-priori drift is smaller than the unit's.
  using Vector6d = Eigen::Matrix<double, 6, 1>;
  const size_t batches = static_cast<size_t>(std::max(options.batches, 2));
  const size_t per_batch = count / batches;
  std::vector<Vector6d> batch_means;
  batch_means.reserve(batches);
  Vector6d sum = Vector6d::Zero(), batch_sum = Vector6d::Zero();
  size_t in_batch = 0;
  for (const StaticSegment& s : segments) {
    for (size_t k = s.first_sample; k < s.end_sample && k < run.samples.size(); ++k) {
      const ImuSample& sample = run.samples[k];
      const Eigen::Matrix3d C_n_b = nav::EulerToDcm(sample.ref_rpy_rad).transpose();
      Vector6d r;
      r << sample.gyro_rad_s - C_n_b * earth_rate_n, sample.acc_mps2 - C_n_b * specific_force_n;
      sum += r;
      if (per_batch == 0 || batch_means.size() == batches) continue;
      batch_sum += r;
      if (++in_batch == per_batch) {
        batch_means.push_back(batch_sum / static_cast<double>(per_batch));
        batch_sum.setZero();
        in_batch = 0;
      }
    }
  }
  Vector6d batch_se = Vector6d::Zero();
  if (batch_means.size() == batches) {
    Vector6d grand = Vector6d::Zero();
    for (const Vector6d& m : batch_means) grand += m;
    grand /= static_cast<double>(batches);
    for (const Vector6d& m : batch_means) batch_se += (m - grand).cwiseAbs2();
    batch_se = (batch_se / (static_cast<double>(batches) * static_cast<double>(batches - 1))).cwiseSqrt();
  }

  const EffectFamily* gyro_turn_on_bias = FindEffectFamily("gyro_turn_on_bias");
  const EffectFamily* acc_turn_on_bias = FindEffectFamily("acc_turn_on_bias");
  if (gyro_turn_on_bias == nullptr || acc_turn_on_bias == nullptr) {
    return absl::InternalError("the effect catalogue has no turn-on bias families");
  }
  StaticConstants out;
  out.static_s = static_s;
  for (int i = 0; i < kSensorAxisCount; ++i) {
    StaticConstant& c = out.axes[static_cast<size_t>(i)];
    const bool gyro = i < 3;
    c.term = EffectTerm{gyro ? gyro_turn_on_bias : acc_turn_on_bias, i % 3, i % 3};
    const SensorTriadModel& triad = gyro ? a_priori.gyro : a_priori.acc;
    c.bias = sum[i] / static_cast<double>(count);
    const GaussMarkov& drift = triad.bias[static_cast<size_t>(c.term.axis)];
    c.std_error = std::max(std::sqrt(MeanVariance(triad.white_noise_density[c.term.axis], drift, static_s)),
                           batch_se[i]);
    c.drift_sigma = drift.sigma;
    c.weakest_batch_bias = std::abs(c.bias);
    for (const Vector6d& m : batch_means) {
      c.weakest_batch_bias = std::min(c.weakest_batch_bias, std::copysign(1.0, c.bias) * m[i]);
    }
    const bool beyond_prior =
        prior == ConstantPrior::kNone || std::abs(c.bias) > options.drift_sigmas * c.drift_sigma;
    c.dominant = beyond_prior &&
                 std::abs(c.bias) > options.standard_errors * c.std_error &&
                 c.weakest_batch_bias > options.batch_share * std::abs(c.bias);
  }
  return out;
}

RemovedConstants RemoveDominantConstants(BenchRun& run, const std::vector<StaticSegment>& segments,
                                                       const ErrorModel& a_priori,
                                                       const DominantConstantOptions& options, ConstantPrior prior,
                                                       std::vector<std::string>& notes) {
  const auto constants = MeasureStaticConstants(run, segments, a_priori, options, prior);
  if (!constants.ok() || !constants->AnyDominant()) return {};
  RemovedConstants removed;
  Eigen::Vector3d& gyro = removed.gyro_rad_s;
  Eigen::Vector3d& acc = removed.acc_mps2;
  std::string list;
  for (const StaticConstant& c : constants->axes) {
    if (!c.dominant) continue;
    (c.term.family->sensor == Sensor::kGyro ? gyro : acc)[c.term.axis] = c.bias;
    ParameterEstimate p;
    p.name = c.term.Name();
    p.value = c.bias;
    p.std_error = c.std_error;
    p.method = EstimationMethod::kStaticMeans;
    p.unit = std::string(c.term.family->unit);
    p.a_priori = 0.0;
    removed.estimates.push_back(std::move(p));
    absl::StrAppend(&list, list.empty() ? "" : ", ",
                    absl::StrFormat("%s %.3g ± %.2g %s (%.0f a-priori drift σ)", c.term.Name(), c.bias, c.std_error,
                                    c.term.family->unit, std::abs(c.bias) / c.drift_sigma));
  }
  for (ImuSample& s : run.samples) {
    s.gyro_rad_s -= gyro;
    s.acc_mps2 -= acc;
  }
  notes.push_back(absl::StrFormat(
      "constant biases %s, measured over %.0f s of static segments against the reference and removed from the "
      "samples before identification: %s",
      prior == ConstantPrior::kNone ? "the run resolves (its a-priori model, fitted to the Allan deviation, bounds none)"
                                    : "far beyond the a-priori model",
      constants->static_s, list));
  return removed;
}

}  // namespace insdiag::engine::ident
