#include "insdiag/engine/filter/forward_filter.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "insdiag/engine/model/flicker_floor.h"
#include "insdiag/engine/nav/wgs84.h"
#include "insdiag/engine/numerics/large_buffers.h"


namespace insdiag::engine {

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

void StoredTransitions::Reserve(size_t epochs, int sensor_states) {
  sensor_states_ = sensor_states;
  A_.reserve(epochs);
  B_.reserve(epochs * static_cast<size_t>(kNavigationStates * sensor_states));
  D_of_epoch_.reserve(epochs);
}

void StoredTransitions::Append(const StateTransition& t) {
  A_.push_back(t.A);
  B_.insert(B_.end(), t.B.data(), t.B.data() + t.B.size());
  if (distinct_D_.empty() || distinct_D_.back().blocks != t.D.blocks) distinct_D_.push_back(t.D);
  D_of_epoch_.push_back(static_cast<int>(distinct_D_.size()) - 1);
}

TransitionView StoredTransitions::operator[](size_t k) const {
  const auto per_epoch = static_cast<size_t>(kNavigationStates * sensor_states_);
  return {A_[k], Eigen::Map<const Eigen::MatrixXd>(B_.data() + k * per_epoch, kNavigationStates, sensor_states_),
          distinct_D_[static_cast<size_t>(D_of_epoch_[k])]};
}

double StoredTransitions::Bytes() const {
  double bytes = static_cast<double>(sizeof(Matrix9d) * A_.size() + sizeof(double) * B_.size() +
                                     sizeof(int) * D_of_epoch_.size());
  for (const SensorBlocks& D : distinct_D_) bytes += static_cast<double>(sizeof(SensorBlocks::Block) * D.blocks.size());
  return bytes;
}

double ForwardPass::BytesPerSample(size_t samples) const {
  if (samples == 0) return 0.0;
  double bytes = 8.0 * static_cast<double>(z.size() + innovation.size() + innovation_variance.size() +
                                           observation_noise.size() + x_pred.size() + x_filt.size() +
                                           P_pred.size() + P_filt.size());
  return (bytes + transitions.Bytes()) / static_cast<double>(samples);
}

double UnsurveyedHeadingSigmaRad(const ErrorModel& model, const Site& site) {
  const double horizontal_earth_rate_rad_s = wgs84::kEarthRateRadS * std::cos(site.latitude_rad);
  double drift_sigma_rad_s = 0.0;
  for (const auto& axis : model.gyro.bias) drift_sigma_rad_s = std::max(drift_sigma_rad_s, axis.sigma);
  const double compassed_rad = drift_sigma_rad_s / std::max(horizontal_earth_rate_rad_s, 1e-300);
  return std::clamp(compassed_rad, model.reference.attitude_sigma_rad, kUnsurveyedHeadingLimitRad);
}

Eigen::MatrixXd InitialCovariance(const ErrorModel& model, const StateLayout& layout, const EpochRun& run) {
  const int n = layout.size();
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(n, n);
  const ReferenceAccuracy& ref = model.reference;
  const StatedAttitudeAccuracy& stated = run.stated_attitude;
  const double level_sigma_rad = stated.level_sigma_rad.value_or(ref.attitude_sigma_rad);
  const double heading_sigma_rad = stated.heading_surveyed ? stated.heading_sigma_rad.value_or(ref.attitude_sigma_rad)
                                                           : UnsurveyedHeadingSigmaRad(model, run.site);
  // ψ is in NED: north and east are the level errors, down the heading's.
  const Eigen::Vector3d attitude_sigma_rad(level_sigma_rad, level_sigma_rad, heading_sigma_rad);
  for (int i = 0; i < 3; ++i) {
    const bool vertical = i == 2;  // NED: down
    const double velocity_sigma_mps = vertical ? ref.vertical_velocity_sigma_mps : ref.horizontal_velocity_sigma_mps;
    const double position_sigma_m = vertical ? ref.vertical_position_sigma_m : ref.horizontal_position_sigma_m;
    P(layout.attitude() + i, layout.attitude() + i) = attitude_sigma_rad[i] * attitude_sigma_rad[i];
    P(layout.velocity() + i, layout.velocity() + i) = velocity_sigma_mps * velocity_sigma_mps;
    P(layout.position() + i, layout.position() + i) = position_sigma_m * position_sigma_m;
  }
  // A counter's residue at the run's start is unknown, uniform over a
  // quantum: the velocity (angle) the counts have not yet delivered, of
  // variance Q² per sensor axis (IEEE Std 952-1997, Annex C), in NED by the
  // start's attitude. It is a start error of the velocity and attitude, not
  // an observation's: the position integrates it from the first sample.
  if (!run.epochs.empty()) {
    const Eigen::Matrix3d& C_b_n = run.epochs.front().C_b_n;
    P.block<3, 3>(layout.velocity(), layout.velocity()).noalias() +=
        C_b_n * model.acc.quantization.cwiseAbs2().asDiagonal() * C_b_n.transpose();
    P.block<3, 3>(layout.attitude(), layout.attitude()).noalias() +=
        C_b_n * model.gyro.quantization.cwiseAbs2().asDiagonal() * C_b_n.transpose();
  }
  for (const SensorState& s : layout.sensor_states()) {
    double var = 0.0;
    switch (s.dynamics) {
      case StateDynamics::kGaussMarkov: {
        const double sigma = (s.sensor == Sensor::kGyro ? model.gyro : model.acc).bias[s.axis].sigma;
        var = sigma * sigma;
        break;
      }
      case StateDynamics::kFlickerComponent: {
        const double sigma = FlickerComponentOf(model, s.sensor, s.axis, s.parameter).sigma;
        var = sigma * sigma;
        break;
      }
      case StateDynamics::kConstant:
      case StateDynamics::kDecaying: {
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

EpochFilter::EpochFilter(const ErrorModel& model, const StateLayout& layout, const EpochRun& run)
    : model_(model), run_(run), transitions_(model, layout, run), rows_(ObservationRows(layout)) {
  const int n = layout.size();
  x_ = Eigen::VectorXd::Zero(n);
  P_ = InitialCovariance(model, layout, run);
  PH_.resize(n);
  gain_.resize(n);
  half_joseph_.resize(n);
}

void EpochFilter::Step(int index, ForwardPass* pass, FilterObserver* observer) {
  const EpochInterval& e = run_.epochs[static_cast<size_t>(index)];
  const IntervalTransition& tr = transitions_.Build(e);
  tr.PropagateMean(x_);
  tr.PropagateCovariance(P_);
  if (observer != nullptr) observer->OnPrediction(index, e, tr);
  const auto k = static_cast<Eigen::Index>(index);
  if (pass != nullptr) {
    pass->transitions.Append(tr);  // Φ alone
    pass->x_pred.row(k) = x_.transpose();
    PackSymmetric(P_, pass->P_pred.row(k).data());
  }
  const ObservationNoise noise = ObservationNoiseAt(e);
  for (int c = 0; c < kChannelCount; ++c) {
    if (IsAttitudeChannel(c) && !e.attitude_observed) {
      // Not observed: ν = S = r = 0 in the pass (ForwardPass::Observed).
      if (pass != nullptr) {
        pass->z(k, c) = e.z[static_cast<size_t>(c)];
        pass->innovation(k, c) = 0.0;
        pass->innovation_variance(k, c) = 0.0;
        pass->observation_noise(k, c) = 0.0;
      }
      continue;
    }
    const ObservationRow& h = rows_[static_cast<size_t>(c)];
    const double r = noise[static_cast<size_t>(c)];
    // P is kept in its lower triangle through the updates: column `state`
    // is its row left of the diagonal and its column from the diagonal down.
    const auto s = static_cast<Eigen::Index>(h.state);
    PH_.head(s) = h.sign * P_.row(s).head(s).transpose();
    PH_.tail(PH_.size() - s) = h.sign * P_.col(s).tail(PH_.size() - s);
    const double S = h.sign * PH_[h.state] + r;
    const double nu = e.z[static_cast<size_t>(c)] - h.sign * x_[h.state];
    gain_ = PH_ / S;
    x_ += gain_ * nu;
    // The expanded Joseph form (header) as a symmetric rank-two update,
    // P += K wᵀ + w Kᵀ with w = ½ S K − Phᵀ, of the lower triangle alone.
    half_joseph_ = 0.5 * S * gain_ - PH_;
    P_.selfadjointView<Eigen::Lower>().rankUpdate(gain_, half_joseph_);
    log_likelihood_ += -0.5 * (std::log(2.0 * std::numbers::pi * S) + nu * nu / S);
    ++scalar_updates_;
    if (pass != nullptr) {
      pass->z(k, c) = e.z[static_cast<size_t>(c)];
      pass->innovation(k, c) = nu;
      pass->innovation_variance(k, c) = S;
      pass->observation_noise(k, c) = r;
    }
    if (observer != nullptr) observer->OnScalarUpdate(c, h, gain_, nu, S);
  }
  P_.triangularView<Eigen::StrictlyUpper>() = P_.transpose();
  if (pass != nullptr) {
    pass->x_filt.row(k) = x_.transpose();
    PackSymmetric(P_, pass->P_filt.row(k).data());
  }
  navigation_estimate_ = x_.head<kNavigationStates>();
  if (observer != nullptr) observer->OnEpochUpdated(index, e);
}

EpochFilter::ObservationNoise EpochFilter::ObservationNoiseAt(const EpochInterval& e) const {
  const ReferenceAccuracy& ref = model_.reference;
  const Eigen::Vector3d position_sigma_m(ref.horizontal_position_sigma_m, ref.horizontal_position_sigma_m,
                                         ref.vertical_position_sigma_m);
  const Eigen::Vector3d velocity_sigma_mps(ref.horizontal_velocity_sigma_mps, ref.horizontal_velocity_sigma_mps,
                                           ref.vertical_velocity_sigma_mps);
  const double readout = std::max(ref.attitude_readout_sigma_rad, kAttitudeRoundingRad);
  const double r_attitude = readout * readout;
  // The INS velocity and attitude carry the current sub-quantum remainder of
  // each accelerometer's and gyro's increment, white with variance Q² (IEEE
  // Std 952, Annex C), rotated to NED by the body attitude.
  const Eigen::Vector3d acc_quantization_var = model_.acc.quantization.cwiseAbs2();
  const Eigen::Vector3d gyro_quantization_var = model_.gyro.quantization.cwiseAbs2();
  ObservationNoise r{};
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d row_squared = e.C_b_n.row(i).transpose().cwiseAbs2();
    r[static_cast<size_t>(kPositionChannel + i)] = position_sigma_m[i] * position_sigma_m[i];
    r[static_cast<size_t>(kVelocityChannel + i)] =
        velocity_sigma_mps[i] * velocity_sigma_mps[i] + row_squared.dot(acc_quantization_var);
    r[static_cast<size_t>(kAttitudeChannel + i)] = r_attitude + row_squared.dot(gyro_quantization_var);
  }
  return r;
}

void EpochFilter::ApplyFeedback(const NavigationVector& u) { x_.head<kNavigationStates>() -= u; }

absl::StatusOr<ForwardPass> RunForwardFilter(const EpochRun& run, const ErrorModel& model, FilterObserver* observer) {
  numerics::KeepLargeBuffersForReuse();
  if (auto st = ValidateErrorModel(model); !st.ok()) return st;
  if (run.epochs.empty()) return absl::InvalidArgumentError("the condensed run has no epochs");
  const StateLayout layout(model);
  const int n = layout.size();
  ForwardPass out;
  out.state_size = n;
  const auto K = static_cast<Eigen::Index>(run.epochs.size());
  out.epoch_time_s.reserve(run.epochs.size());
  out.epoch_start_s.reserve(run.epochs.size());
  out.epoch_sample.reserve(run.epochs.size());
  for (const EpochInterval& e : run.epochs) {
    out.epoch_time_s.push_back(e.time_s);
    out.epoch_start_s.push_back(e.start_s);
    out.epoch_sample.push_back(e.sample);
  }
  out.z.resize(K, kChannelCount);
  out.innovation.resize(K, kChannelCount);
  out.innovation_variance.resize(K, kChannelCount);
  out.observation_noise.resize(K, kChannelCount);
  out.x_pred.resize(K, n);
  out.x_filt.resize(K, n);
  out.P_pred.resize(K, PackedSize(n));
  out.P_filt.resize(K, PackedSize(n));
  out.transitions.Reserve(run.epochs.size(), n - kNavigationStates);
  EpochFilter filter(model, layout, run);
  out.x0 = filter.x();
  out.P0 = filter.P();
  for (int k = 0; k < run.size(); ++k) {
    filter.Step(k, &out, observer);
    filter.ApplyFeedback(run.epochs[static_cast<size_t>(k)].feedback);
  }
  out.log_likelihood = filter.log_likelihood();
  out.scalar_updates = filter.scalar_updates();
  out.duration_s = run.duration_s;
  return out;
}

absl::StatusOr<ForwardPass> RunForwardFilter(const BenchRun& run, const ErrorModel& model,
                                             const FilterOptions& options, FilterObserver* observer) {
  if (auto st = options.Validate(); !st.ok()) return st;
  auto condensed = CondenseRun(run, model, options.update_interval_s);
  if (!condensed.ok()) return condensed.status();
  return RunForwardFilter(*condensed, model, observer);
}

}  // namespace insdiag::engine
