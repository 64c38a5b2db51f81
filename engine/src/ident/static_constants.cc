#include "insdiag/engine/ident/static_constants.h"

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

// The standard error of each axis' mean from the data: the scatter of the
// means of `batches` equal batches of the static samples (batch means,
// Law & Kelton, Simulation Modeling and Analysis, 3rd ed., §9.5.3). It
// stands in when the a-priori drift is smaller than the unit's.
Eigen::Matrix<double, 6, 1> BatchMeanStandardErrors(const std::vector<Eigen::Matrix<double, 6, 1>>& residuals,
                                                    int batches) {
  Eigen::Matrix<double, 6, 1> se = Eigen::Matrix<double, 6, 1>::Zero();
  const size_t per_batch = residuals.size() / static_cast<size_t>(batches);
  if (per_batch == 0) return se;
  std::vector<Eigen::Matrix<double, 6, 1>> means(static_cast<size_t>(batches), Eigen::Matrix<double, 6, 1>::Zero());
  Eigen::Matrix<double, 6, 1> grand = Eigen::Matrix<double, 6, 1>::Zero();
  for (size_t b = 0; b < means.size(); ++b) {
    for (size_t k = b * per_batch; k < (b + 1) * per_batch; ++k) means[b] += residuals[k];
    means[b] /= static_cast<double>(per_batch);
    grand += means[b];
  }
  grand /= static_cast<double>(batches);
  for (const auto& m : means) se += (m - grand).cwiseAbs2();
  return (se / (static_cast<double>(batches) * (batches - 1))).cwiseSqrt();
}

}  // namespace

std::string StaticConstant::TermName() const {
  return std::string(sensor == Sensor::kGyro ? "gyro" : "acc") + "_turn_on_bias." + "xyz"[axis];
}

std::string StaticConstant::Unit() const { return sensor == Sensor::kGyro ? "rad/s" : "m/s^2"; }

bool StaticConstants::AnyDominant() const {
  return std::any_of(axes.begin(), axes.end(), [](const StaticConstant& c) { return c.dominant; });
}

absl::StatusOr<StaticConstants> MeasureStaticConstants(const BenchRun& run,
                                                       const std::vector<StaticSegment>& segments,
                                                       const ErrorModel& a_priori,
                                                       const DominantConstantOptions& options) {
  const Site& site = run.metadata.site;
  const Eigen::Vector3d earth_rate_n = wgs84::EarthRateNed(site.latitude_rad);
  const Eigen::Vector3d specific_force_n(0.0, 0.0, -wgs84::NormalGravityMps2(site.latitude_rad, site.height_m));

  // Reading minus a perfect unit's, per static sample (gyro x, y, z, acc x, y, z).
  std::vector<Eigen::Matrix<double, 6, 1>> residuals;
  Eigen::Matrix<double, 6, 1> sum = Eigen::Matrix<double, 6, 1>::Zero();
  double static_s = 0.0;
  for (const StaticSegment& s : segments) {
    for (size_t k = s.first_sample; k < s.end_sample && k < run.samples.size(); ++k) {
      const ImuSample& sample = run.samples[k];
      const Eigen::Matrix3d C_n_b = nav::EulerToDcm(sample.ref_rpy_rad).transpose();
      Eigen::Matrix<double, 6, 1> r;
      r << sample.gyro_rad_s - C_n_b * earth_rate_n, sample.acc_mps2 - C_n_b * specific_force_n;
      residuals.push_back(r);
      sum += r;
    }
    static_s += s.end_s - s.start_s;
  }
  const size_t count = residuals.size();
  if (count == 0 || !(static_s > 0.0)) {
    return absl::FailedPreconditionError("the run has no static segment to measure its constant biases on");
  }

  const Eigen::Matrix<double, 6, 1> batch_se = BatchMeanStandardErrors(residuals, options.batches);
  StaticConstants out;
  out.static_s = static_s;
  for (int i = 0; i < kSensorAxisCount; ++i) {
    StaticConstant& c = out.axes[static_cast<size_t>(i)];
    c.sensor = i < 3 ? Sensor::kGyro : Sensor::kAccelerometer;
    c.axis = i % 3;
    const SensorTriadModel& triad = c.sensor == Sensor::kGyro ? a_priori.gyro : a_priori.acc;
    c.bias = sum[i] / static_cast<double>(count);
    c.std_error = std::max(std::sqrt(MeanVariance(triad.white_noise_density[c.axis],
                                                  triad.bias[static_cast<size_t>(c.axis)], static_s)),
                           batch_se[i]);
    c.drift_sigma = triad.bias[static_cast<size_t>(c.axis)].sigma;
    c.dominant = std::abs(c.bias) > options.drift_sigmas * c.drift_sigma &&
                 std::abs(c.bias) > options.standard_errors * c.std_error;
  }
  return out;
}

void RemoveDominantConstants(const StaticConstants& constants, BenchRun& run) {
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero(), acc = Eigen::Vector3d::Zero();
  for (const StaticConstant& c : constants.axes) {
    if (c.dominant) (c.sensor == Sensor::kGyro ? gyro : acc)[c.axis] = c.bias;
  }
  for (ImuSample& s : run.samples) {
    s.gyro_rad_s -= gyro;
    s.acc_mps2 -= acc;
  }
}

std::vector<ParameterEstimate> DominantConstantEstimates(const StaticConstants& constants) {
  std::vector<ParameterEstimate> out;
  for (const StaticConstant& c : constants.axes) {
    if (!c.dominant) continue;
    ParameterEstimate p;
    p.name = c.TermName();
    p.value = c.bias;
    p.std_error = c.std_error;
    p.method = "STATIC";
    p.unit = c.Unit();
    p.a_priori = 0.0;
    out.push_back(std::move(p));
  }
  return out;
}

}  // namespace insdiag::engine::ident
