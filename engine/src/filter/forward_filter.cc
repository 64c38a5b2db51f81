#include "insdiag/engine/filter/forward_filter.h"

#include <cmath>
#include <numbers>

#include "insdiag/engine/nav/rotation.h"
#include "insdiag/engine/nav/strapdown.h"
#include "insdiag/engine/nav/wgs84.h"

namespace insdiag::engine {
namespace {

absl::Status ValidateModel(const ErrorModel& model) {
  for (const SensorTriadModel* triad : {&model.gyro, &model.acc}) {
    for (const GaussMarkov& gm : triad->bias) {
      if (!(gm.sigma >= 0.0) || (gm.sigma > 0.0 && !(gm.tau_s > 0.0))) {
        return absl::InvalidArgumentError("error model: a Gauss–Markov drift needs σ ≥ 0 and τ > 0");
      }
    }
    if (!(triad->white_noise_density.array() >= 0.0).all() || !(triad->quantization.array() >= 0.0).all()) {
      return absl::InvalidArgumentError("error model: noise densities and quantisation must be ≥ 0");
    }
  }
  return absl::OkStatus();
}

// Circular mean of two angles (the reference yaw across a sample interval).
double MidAngle(double a, double b) { return a + 0.5 * std::remainder(b - a, 2.0 * std::numbers::pi); }

void FeedBackNavigation(const StateLayout& layout, const Site& site, Eigen::VectorXd& x, nav::NavState& ins) {
  const Eigen::Vector3d psi = x.segment<3>(layout.attitude());
  const Eigen::Vector3d dv = x.segment<3>(layout.velocity());
  const Eigen::Vector3d dr = x.segment<3>(layout.position());
  // C̃ = (I − [ψ×]) C  ⇒  C ≈ exp([ψ×]) C̃.
  ins.q_b_n = (nav::RotationVectorToQuaternion(psi) * ins.q_b_n).normalized();
  ins.v_n_mps -= dv;
  const double rm = wgs84::MeridianRadiusM(site.latitude_rad) + site.height_m;
  const double rn = wgs84::PrimeVerticalRadiusM(site.latitude_rad) + site.height_m;
  ins.latitude_rad -= dr.x() / rm;
  ins.longitude_rad -= dr.y() / (rn * std::cos(site.latitude_rad));
  ins.height_m += dr.z();
  x.head<StateLayout::kNavigationSize>().setZero();
}

}  // namespace

absl::Status FilterOptions::Validate() const {
  if (!(update_interval_s > 0.0)) return absl::InvalidArgumentError("update interval must be positive");
  return absl::OkStatus();
}

int PackedSize(int n) { return n * (n + 1) / 2; }

void PackSymmetric(const Eigen::MatrixXd& P, double* out) {
  const auto n = P.rows();
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = i; j < n; ++j) *out++ = P(i, j);
  }
}

void UnpackSymmetric(const double* in, int n, Eigen::MatrixXd& P) {
  P.resize(n, n);
  for (int i = 0; i < n; ++i) {
    for (int j = i; j < n; ++j) P(i, j) = P(j, i) = *in++;
  }
}

double ForwardPass::BytesPerSample(size_t samples) const {
  if (samples == 0) return 0.0;
  double bytes = 8.0 * static_cast<double>(z.size() + innovation.size() + innovation_variance.size() +
                                           observation_noise.size() + x_pred.size() + x_filt.size() +
                                           P_pred.size() + P_filt.size());
  for (const auto& t : transitions) bytes += 8.0 * (81.0 + static_cast<double>(t.B.size())) + 40.0 * t.D.blocks.size();
  return bytes / static_cast<double>(samples);
}

Eigen::MatrixXd InitialCovariance(const ErrorModel& model, const StateLayout& layout) {
  const int n = layout.size();
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(n, n);
  const ReferenceAccuracy& ref = model.reference;
  for (int i = 0; i < 3; ++i) {
    P(layout.attitude() + i, layout.attitude() + i) = ref.attitude_sigma_rad * ref.attitude_sigma_rad;
    P(layout.velocity() + i, layout.velocity() + i) = ref.velocity_sigma_mps * ref.velocity_sigma_mps;
    P(layout.position() + i, layout.position() + i) = ref.position_sigma_m * ref.position_sigma_m;
  }
  for (const SensorState& s : layout.sensor_states()) {
    double var = 0.0;
    switch (s.dynamics) {
      case StateDynamics::kGaussMarkov: {
        const double sigma = (s.sensor == Sensor::kGyro ? model.gyro : model.acc).bias[s.axis].sigma;
        var = sigma * sigma;
        break;
      }
      case StateDynamics::kConstant: {
        const double sigma = model.effects[static_cast<size_t>(s.effect)].prior_sigma[static_cast<size_t>(s.parameter)];
        var = sigma * sigma;
        break;
      }
      case StateDynamics::kRandomWalk:
        var = 0.0;  // the walk starts at zero with the run; its start value belongs to the drift
        break;
      case StateDynamics::kSecondOrderPair:
      case StateDynamics::kSecondOrderTail: {
        const double sigma = model.effects[static_cast<size_t>(s.effect)].second_order_sigma;
        var = sigma * sigma;
        break;
      }
    }
    P(s.index, s.index) = var;
  }
  return P;
}

absl::StatusOr<ForwardPass> RunForwardFilter(const BenchRun& run, const ErrorModel& model,
                                             const FilterOptions& options, FilterObserver* observer) {
  if (auto st = options.Validate(); !st.ok()) return st;
  if (auto st = ValidateModel(model); !st.ok()) return st;
  if (run.samples.size() < 2) return absl::InvalidArgumentError("a bench run needs at least two samples");

  const StateLayout layout(model);
  const int n = layout.size();
  const Site& site = run.metadata.site;
  const double dt_nominal = run.NominalIntervalS();
  const int samples_per_epoch =
      std::max(1, static_cast<int>(std::lround(options.update_interval_s / dt_nominal)));
  const Matrix9d F = NavigationErrorMatrix(site, layout);
  NavigationDiscretisation nominal = DiscretiseNavigation(F, dt_nominal);
  NavigationDiscretisation irregular = nominal;
  SensorBlocks D_nominal, Qs_nominal, D_irregular, Qs_irregular;
  SensorBlocks::Discretise(model, layout, dt_nominal, D_nominal, Qs_nominal);
  const auto rows = ObservationRows(layout);
  const Eigen::Vector3d acc_quantization_var = model.acc.quantization.cwiseAbs2();
  const double r_position = model.reference.position_sigma_m * model.reference.position_sigma_m;
  const double r_velocity = model.reference.velocity_sigma_mps * model.reference.velocity_sigma_mps;

  const size_t samples = run.samples.size();
  const size_t epochs_expected = (samples - 1 + static_cast<size_t>(samples_per_epoch) - 1) /
                                 static_cast<size_t>(samples_per_epoch);
  ForwardPass out;
  out.state_size = n;
  out.epoch_time_s.reserve(epochs_expected);
  out.epoch_sample.reserve(epochs_expected);
  const auto K = static_cast<Eigen::Index>(epochs_expected);
  out.z.resize(K, kChannelCount);
  out.innovation.resize(K, kChannelCount);
  out.innovation_variance.resize(K, kChannelCount);
  out.observation_noise.resize(K, kChannelCount);
  out.x_pred.resize(K, n);
  out.x_filt.resize(K, n);
  out.P_pred.resize(K, PackedSize(n));
  out.P_filt.resize(K, PackedSize(n));
  out.transitions.reserve(epochs_expected);

  nav::NavState ins;
  ins.q_b_n = Eigen::Quaterniond(nav::EulerToDcm(run.samples[0].ref_rpy_rad));
  ins.latitude_rad = site.latitude_rad;
  ins.longitude_rad = site.longitude_rad;
  ins.height_m = site.height_m;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  Eigen::MatrixXd P = InitialCovariance(model, layout);
  out.x0 = x;
  out.P0 = P;
  Eigen::VectorXd PH(n), gain(n), half_joseph(n);

  IntervalAccumulator accumulator(model, layout, nominal, samples_per_epoch);
  const double temperature0 = run.samples[0].temp_degc;
  nav::ImuIncrement previous{run.samples[0].gyro_rad_s * dt_nominal, run.samples[0].acc_mps2 * dt_nominal};
  int in_interval = 0;

  for (size_t k = 1; k < samples; ++k) {
    const ImuSample& s = run.samples[k];
    const double dt = s.t_s - run.samples[k - 1].t_s;
    const NavigationDiscretisation* disc = &nominal;
    const SensorBlocks* D = &D_nominal;
    const SensorBlocks* Qs = &Qs_nominal;
    if (std::abs(dt - dt_nominal) > 1e-9 * dt_nominal) {
      // An irregular sample interval (within the format's tolerance): exact maps for it.
      if (std::abs(dt - irregular.dt_s) > 1e-12 * dt_nominal) {
        irregular = DiscretiseNavigation(F, dt);
        SensorBlocks::Discretise(model, layout, dt, D_irregular, Qs_irregular);
      }
      disc = &irregular;
      D = &D_irregular;
      Qs = &Qs_irregular;
    }
    const nav::ImuIncrement current{s.gyro_rad_s * dt, s.acc_mps2 * dt};
    const Eigen::Quaterniond q_start = ins.q_b_n;
    ins = nav::PropagateStrapdown(ins, current, previous, dt);
    previous = current;

    RegressorInputs inputs;
    inputs.gyro_rad_s = s.gyro_rad_s;
    inputs.acc_mps2 = s.acc_mps2;
    inputs.temperature_delta_degc = run.has_temperature ? s.temp_degc - temperature0 : 0.0;
    inputs.yaw_rad = MidAngle(run.samples[k - 1].ref_rpy_rad.z(), s.ref_rpy_rad.z());
    const Eigen::Matrix3d C_mid = nav::Midway(q_start, ins.q_b_n).toRotationMatrix();
    const SampleCoupling& coupling = accumulator.AddSample(*disc, *D, *Qs, C_mid, inputs);
    if (observer != nullptr) observer->OnSample(*disc, coupling);
    ++in_interval;
    if (in_interval < samples_per_epoch && k + 1 < samples) continue;

    // ---- epoch: predict over the interval, then the channel-wise updates ----
    in_interval = 0;
    const IntervalTransition& tr = accumulator.Finish();
    tr.PropagateMean(x);
    tr.PropagateCovariance(P);
    if (observer != nullptr) observer->OnPrediction(tr);
    const auto e = static_cast<Eigen::Index>(out.epoch_time_s.size());
    out.epoch_time_s.push_back(s.t_s);
    out.epoch_sample.push_back(static_cast<int>(k));
    out.transitions.push_back({tr.A, tr.B, tr.D});
    out.x_pred.row(e) = x.transpose();
    PackSymmetric(P, out.P_pred.row(e).data());

    const std::array<double, kChannelCount> z = Observe(ins, site);
    const Eigen::Matrix3d C_now = ins.q_b_n.toRotationMatrix();
    for (int c = 0; c < kChannelCount; ++c) {
      const ObservationRow& h = rows[static_cast<size_t>(c)];
      double r = r_position;
      if (c >= 3) {
        // Velocity quantisation: the INS velocity carries the current sub-quantum
        // remainder of each accelerometer, white with variance Q² (IEEE 952).
        r = r_velocity + (C_now.row(c - 3).transpose().cwiseAbs2().dot(acc_quantization_var));
      }
      PH = h.sign * P.col(h.state);
      const double S = h.sign * PH[h.state] + r;
      const double nu = z[static_cast<size_t>(c)] - h.sign * x[h.state];
      gain = PH / S;
      x += gain * nu;
      // The expanded Joseph form (header) as a symmetric rank-two update,
      // P += K wᵀ + w Kᵀ with w = ½ S K − Phᵀ: two outer products, not three.
      half_joseph = 0.5 * S * gain - PH;
      P.noalias() += gain * half_joseph.transpose();
      P.noalias() += half_joseph * gain.transpose();
      out.log_likelihood += -0.5 * (std::log(2.0 * std::numbers::pi * S) + nu * nu / S);
      ++out.scalar_updates;
      out.z(e, c) = z[static_cast<size_t>(c)];
      out.innovation(e, c) = nu;
      out.innovation_variance(e, c) = S;
      out.observation_noise(e, c) = r;
      if (observer != nullptr) observer->OnScalarUpdate(c, h, gain, nu, S);
    }
    P = 0.5 * (P + P.transpose()).eval();
    out.x_filt.row(e) = x.transpose();
    PackSymmetric(P, out.P_filt.row(e).data());
    FeedBackNavigation(layout, site, x, ins);
    accumulator.Reset();
  }
  out.duration_s = run.DurationS();
  return out;
}

}  // namespace insdiag::engine
