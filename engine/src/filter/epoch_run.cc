#include "insdiag/engine/filter/epoch_run.h"

#include <cmath>
#include <memory>
#include <numbers>
#include <utility>

#include "insdiag/engine/filter/forward_filter.h"
#include "insdiag/engine/filter/model_transitions.h"
#include "insdiag/engine/filter/observation.h"
#include "insdiag/engine/nav/rotation.h"
#include "insdiag/engine/nav/strapdown.h"
#include "insdiag/engine/nav/table_motion.h"
#include "insdiag/engine/nav/wgs84.h"

namespace insdiag::engine {
namespace {

// Circular mean of two angles (the reference yaw across a sample interval).
double MidAngle(double a, double b) { return a + 0.5 * std::remainder(b - a, 2.0 * std::numbers::pi); }

// The constant catalogue parameters grouped by term, which share one
// regressor evaluation per sample.
struct TermColumns {
  EffectTerm term;
  int first = 0;
  int count = 1;
  int axis = 0;  // SensorAxisIndex of the term's sensor output
};

std::vector<TermColumns> GroupByTerm(const std::vector<ConstantParameter>& columns) {
  std::vector<TermColumns> out;
  for (size_t i = 0; i < columns.size(); ++i) {
    if (!out.empty() && out.back().term == columns[i].term) {
      ++out.back().count;
      continue;
    }
    out.push_back({columns[i].term, static_cast<int>(i), 1,
                   SensorAxisIndex(columns[i].term.family->sensor, columns[i].term.axis)});
  }
  return out;
}

// Accumulates one interval's samples in interval-start coordinates (y =
// T_j⁻¹ x, where the navigation transition is the identity) and maps them to
// the interval's end at Finish. Preallocated: nothing is allocated per sample.
class IntervalCondenser {
 public:
  IntervalCondenser(const NavigationDiscretisation& nominal, int samples_per_interval, int constant_columns,
                    std::vector<TermColumns> terms)
      : nominal_dt_(nominal.dt_s), terms_(std::move(terms)) {
    const auto capacity = static_cast<size_t>(std::max(1, samples_per_interval) + 2);
    power_.resize(capacity + 1);
    inverse_power_.resize(capacity + 1);
    power_[0].setIdentity();
    inverse_power_[0].setIdentity();
    for (size_t j = 1; j <= capacity; ++j) {
      power_[j] = nominal.A * power_[j - 1];
      inverse_power_[j] = inverse_power_[j - 1] * nominal.A_inverse;
    }
    constants_.setZero(9, constant_columns);
    Reset(0.0);
  }

  void Reset(double start_s) {
    start_s_ = start_s;
    samples_ = 0;
    regular_ = true;
    dt_sum_ = 0.0;
    T_.setIdentity();
    T_inverse_.setIdentity();
    for (auto& m : moments_) m.setZero();
    for (auto& w : white_) w.setZero();
    for (auto& q : quantisation_) q.setZero();
    constants_.setZero();
    gram_.setZero();
  }

  // One sample over (t_prev, t_prev + Δt] held at reference attitude C_mid
  // with regressor inputs `in`.
  void AddSample(const NavigationDiscretisation& nav, double t_prev_s, const Eigen::Matrix3d& C_mid,
                 const RegressorInputs& in) {
    ++samples_;
    const auto j = static_cast<size_t>(samples_);
    const double dt = nav.dt_s;
    dt_sum_ += dt;
    const bool nominal_step = std::abs(dt - nominal_dt_) <= 1e-9 * nominal_dt_;
    if (regular_ && (!nominal_step || j >= power_.size())) {
      T_ = power_[j - 1];
      T_inverse_ = inverse_power_[j - 1];
      regular_ = false;
    }
    const Matrix9d* T_inverse = &inverse_power_[std::min(j, power_.size() - 1)];
    if (!regular_) {
      const Matrix9d T = nav.A.lazyProduct(T_);
      const Matrix9d T_inv = T_inverse_.lazyProduct(nav.A_inverse);
      T_ = T;
      T_inverse_ = T_inv;
      T_inverse = &T_inverse_;
    }
    // b_j: a unit error on each sensor axis held over the sample, in
    // interval-start coordinates (error_dynamics.h).
    const Matrix93d gyro_in = -T_inverse->lazyProduct(nav.Gamma.middleCols<3>(0));
    const Matrix93d acc_in = T_inverse->lazyProduct(nav.Gamma.middleCols<3>(3));
    Matrix96d b;
    b.leftCols<3>().noalias() = gyro_in.lazyProduct(C_mid);
    b.rightCols<3>().noalias() = acc_in.lazyProduct(C_mid);

    const double s = t_prev_s - start_s_;
    double sp = 1.0;
    for (int p = 0; p < kCouplingMoments; ++p, sp *= s) moments_[static_cast<size_t>(p)].noalias() += sp * b;
    double sq = 1.0;
    for (int p = 0; p < 2 * kCouplingMoments - 1; ++p, sq *= s) {
      for (int r = std::max(0, p - kCouplingDegree); r <= std::min(p, kCouplingDegree); ++r) gram_(r, p - r) += sq;
    }
    const double inv_dt = 1.0 / dt;
    for (int a = 0; a < kSensorAxisCount; ++a) {
      const NavigationVector col = b.col(a);
      white_[static_cast<size_t>(a)].noalias() += (inv_dt * col).lazyProduct(col.transpose());
    }
    // Velocity quantisation: the position integrates each sample's carried
    // remainder, white with variance Q² per axis (IEEE Std 952, Annex C).
    const Matrix93d to_position = T_inverse->middleCols<3>(6).lazyProduct(C_mid);
    for (int a = 0; a < 3; ++a) {
      const NavigationVector col = to_position.col(a) * dt;
      quantisation_[static_cast<size_t>(a)].noalias() += col.lazyProduct(col.transpose());
    }
    double r[2];
    for (const TermColumns& t : terms_) {
      EvaluateRegressor(t.term, in, r);
      for (int k = 0; k < t.count; ++k) constants_.col(t.first + k).noalias() += b.col(t.axis) * r[k];
    }
  }

  int samples() const { return samples_; }

  // The interval in end coordinates.
  void Finish(EpochInterval& e) {
    const Matrix9d& T = regular_ ? power_[static_cast<size_t>(samples_)] : T_;
    e.start_s = start_s_;
    e.samples = samples_;
    e.sample_interval_s = samples_ > 0 ? dt_sum_ / samples_ : nominal_dt_;
    e.A = T;
    for (int p = 0; p < kCouplingMoments; ++p) {
      e.moments[static_cast<size_t>(p)].noalias() = T.lazyProduct(moments_[static_cast<size_t>(p)]);
    }
    e.gram = gram_;
    for (int a = 0; a < kSensorAxisCount; ++a) {
      const Matrix9d TW = T.lazyProduct(white_[static_cast<size_t>(a)]);
      e.white[static_cast<size_t>(a)] = Pack9(TW.lazyProduct(T.transpose()));
    }
    for (int a = 0; a < 3; ++a) {
      const Matrix9d TQ = T.lazyProduct(quantisation_[static_cast<size_t>(a)]);
      e.quantisation[static_cast<size_t>(a)] = Pack9(TQ.lazyProduct(T.transpose()));
    }
    e.constants.noalias() = T * constants_;
  }

 private:
  double nominal_dt_;
  std::vector<TermColumns> terms_;
  std::vector<Matrix9d> power_, inverse_power_;
  double start_s_ = 0.0;
  int samples_ = 0;
  bool regular_ = true;
  double dt_sum_ = 0.0;
  Matrix9d T_, T_inverse_;
  std::array<Matrix96d, kCouplingMoments> moments_;
  std::array<Matrix9d, kSensorAxisCount> white_;
  std::array<Matrix9d, 3> quantisation_;
  Eigen::Matrix<double, kNavigationStates, Eigen::Dynamic> constants_;
  Eigen::Matrix<double, kCouplingMoments, kCouplingMoments> gram_;
};

void FeedBackNavigation(const Site& site, const NavigationVector& u, nav::NavState& ins) {
  // C̃ = (I − [ψ×]) C  ⇒  C ≈ exp([ψ×]) C̃.
  ins.q_b_n = (nav::RotationVectorToQuaternion(u.segment<3>(0)) * ins.q_b_n).normalized();
  ins.v_n_mps -= u.segment<3>(3);
  const double rm = wgs84::MeridianRadiusM(site.latitude_rad) + site.height_m;
  const double rn = wgs84::PrimeVerticalRadiusM(site.latitude_rad) + site.height_m;
  ins.latitude_rad -= u[6] / rm;
  ins.longitude_rad -= u[7] / (rn * std::cos(site.latitude_rad));
  ins.height_m += u[8];
}

}  // namespace

Matrix9d Unpack9(const PackedSymmetric9d& packed) {
  Matrix9d m;
  int k = 0;
  for (int i = 0; i < 9; ++i) {
    for (int j = i; j < 9; ++j) m(i, j) = m(j, i) = packed[k++];
  }
  return m;
}

PackedSymmetric9d Pack9(const Matrix9d& m) {
  PackedSymmetric9d packed;
  int k = 0;
  for (int i = 0; i < 9; ++i) {
    for (int j = i; j < 9; ++j) packed[k++] = 0.5 * (m(i, j) + m(j, i));
  }
  return packed;
}

int EpochRun::ConstantColumn(const EffectTerm& term, int parameter) const {
  for (size_t i = 0; i < constant_columns.size(); ++i) {
    if (constant_columns[i].term == term && constant_columns[i].parameter == parameter) return static_cast<int>(i);
  }
  return -1;
}

double EpochRun::BytesPerEpoch() const {
  if (epochs.empty()) return 0.0;
  const EpochInterval& e = epochs.front();
  return static_cast<double>(sizeof(EpochInterval)) + 8.0 * static_cast<double>(e.constants.size());
}

// Everything the condensation carries from one sample to the next.
struct RunCondenser::State {
  State(const BenchRun& run_in, const ErrorModel& pilot_in, double update_interval_s,
        double nominal_interval_s, FilterObserver* observer_in,
        const nav::RunCompensations* compensations_in)
      : run(run_in),
        pilot(pilot_in),
        layout(pilot),
        out(Header(run_in, update_interval_s, nominal_interval_s)),
        F(NavigationErrorMatrix(run_in.metadata.site, layout)),
        nominal(DiscretiseNavigation(F, layout, nominal_interval_s)),
        irregular(nominal),
        condenser(nominal, out.samples_per_epoch, static_cast<int>(out.constant_columns.size()),
                  GroupByTerm(out.constant_columns)),
        pilot_filter(pilot, layout, out),
        motion(run_in),
        compensations(compensations_in),
        observer(observer_in),
        temperature0(run_in.samples[0].temp_degc),
        attitude_declared(run_in.metadata.DeclaredAttitudeReadout()),
        still_tolerance_rad(StillToleranceRad(pilot_in.reference)) {
    const auto per_epoch = static_cast<size_t>(out.samples_per_epoch);
    out.epochs.reserve((run.samples.size() + per_epoch - 1) / per_epoch);
    StartSegment(0);
  }

  static EpochRun Header(const BenchRun& run, double requested_update_interval_s,
                         double nominal_interval_s) {
    EpochRun out;
    const double update_interval_s =
        UpdateIntervalForRun(requested_update_interval_s, nominal_interval_s);
    out.site = run.metadata.site;
    out.stated_attitude = run.metadata.AttitudeAccuracy();
    out.update_interval_s = update_interval_s;
    out.sample_interval_s = nominal_interval_s;
    out.constant_columns = AllConstantParameters();
    out.samples_per_epoch = std::max(1, static_cast<int>(std::lround(update_interval_s / nominal_interval_s)));
    return out;
  }

  // The mechanisation starts at a segment's first sample, at rest at the
  // site in the reference attitude; that sample's increment is not used
  // (for the run's first segment it precedes the start; for a later one it
  // covers the unrecorded move).
  void StartSegment(size_t k) {
    const Site& site = run.metadata.site;
    ins = nav::NavState{};
    ins.q_b_n = Eigen::Quaterniond(nav::EulerToDcm(run.samples[k].ref_rpy_rad));
    ins.latitude_rad = site.latitude_rad;
    ins.longitude_rad = site.longitude_rad;
    ins.height_m = site.height_m;
    q_ref_previous = ins.q_b_n;
    segment_start_rpy = run.samples[k].ref_rpy_rad;
    attitude_read = attitude_declared.value_or(false);
    StartInterval(k);
  }

  void StartInterval(size_t k) {
    condenser.Reset(run.samples[k].t_s);
    interval_start_rpy = run.samples[k].ref_rpy_rad;
    interval_still = attitude_read;
  }

  // The reference attitude of sample k still at the interval's start (StillToleranceRad).
  bool StillAtIntervalStart(const Eigen::Vector3d& rpy) const {
    for (int i = 0; i < 3; ++i) {
      if (std::abs(std::remainder(rpy[i] - interval_start_rpy[i], 2.0 * std::numbers::pi)) > still_tolerance_rad) {
        return false;
      }
    }
    return true;
  }

  // Sample k's interval into the current epoch; closes the epoch when it is
  // full, the run ends (`run_complete` and k is last) or a segment starts next.
  void Condense(size_t k, bool run_complete) {
    if (run.StartsSegment(k)) {
      StartSegment(k);
      segment_starts = true;
      return;
    }
    const Site& site = run.metadata.site;
    const double dt_nominal = out.sample_interval_s;
    const ImuSample& s = run.samples[k];
    const double t_prev = run.samples[k - 1].t_s;
    const double dt = s.t_s - t_prev;
    const NavigationDiscretisation* disc = &nominal;
    if (std::abs(dt - dt_nominal) > 1e-9 * dt_nominal) {
      // An irregular sample interval (within the format's tolerance): exact maps for it.
      if (std::abs(dt - irregular.dt_s) > 1e-12 * dt_nominal)
        irregular = DiscretiseNavigation(F, layout, dt);
      disc = &irregular;
    }
    const nav::ImuIncrement current{s.gyro_rad_s * dt, s.acc_mps2 * dt};
    ins = nav::PropagateStrapdown(ins, current, compensations != nullptr ? compensations->At(k) : motion.Compensation(k),
                                  dt);

    const Eigen::Quaterniond q_ref(nav::EulerToDcm(s.ref_rpy_rad));
    RegressorInputs inputs;
    inputs.gyro_rad_s = s.gyro_rad_s;
    inputs.acc_mps2 = s.acc_mps2;
    inputs.temperature_delta_degc = run.has_temperature ? s.temp_degc - temperature0 : 0.0;
    inputs.yaw_rad = MidAngle(run.samples[k - 1].ref_rpy_rad.z(), s.ref_rpy_rad.z());
    condenser.AddSample(*disc, t_prev, nav::Midway(q_ref_previous, q_ref).toRotationMatrix(), inputs);
    q_ref_previous = q_ref;
    // Undeclared, the attitude is read from its first move on (bench_run.h).
    if (!attitude_read && !attitude_declared.has_value() && s.ref_rpy_rad != segment_start_rpy) attitude_read = true;
    interval_still = interval_still && StillAtIntervalStart(s.ref_rpy_rad);
    const bool last = run_complete && k + 1 == run.samples.size();
    if (condenser.samples() < out.samples_per_epoch && !last && !run.StartsSegment(k + 1)) return;

    EpochInterval& e = out.epochs.emplace_back();
    condenser.Finish(e);
    e.starts_segment = std::exchange(segment_starts, false);
    e.time_s = s.t_s;
    e.sample = static_cast<int>(k);
    e.C_b_n = q_ref.toRotationMatrix();
    e.z = Observe(ins, site, e.C_b_n);
    e.attitude_observed = interval_still;
    pilot_filter.Step(out.size() - 1, nullptr, observer);
    e.feedback = pilot_filter.navigation_estimate();
    pilot_filter.ApplyFeedback(e.feedback);
    FeedBackNavigation(site, e.feedback, ins);
    StartInterval(k);
  }

  const BenchRun& run;
  const ErrorModel pilot;
  const StateLayout layout;
  EpochRun out;
  const Matrix9d F;
  const NavigationDiscretisation nominal;
  NavigationDiscretisation irregular;
  IntervalCondenser condenser;
  EpochFilter pilot_filter;  // stepped epoch by epoch beside the mechanisation
  nav::ReferenceMotion motion;
  const nav::RunCompensations* compensations;  // the run's, when given: else from `motion`
  FilterObserver* observer;
  const double temperature0;
  nav::NavState ins;
  Eigen::Quaterniond q_ref_previous;
  bool segment_starts = false;
  size_t next_sample = 1;
  const std::optional<bool> attitude_declared;
  bool attitude_read = false;
  Eigen::Vector3d segment_start_rpy = Eigen::Vector3d::Zero();
  const double still_tolerance_rad;
  Eigen::Vector3d interval_start_rpy = Eigen::Vector3d::Zero();
  bool interval_still = false;
};

double StillToleranceRad(const ReferenceAccuracy& reference) {
  return kStillToleranceReadoutSigmas * std::max(reference.attitude_readout_sigma_rad, kAttitudeRoundingRad);
}

double UpdateIntervalForRun(double requested_update_interval_s, double nominal_interval_s) {
  const double shortest_s = kMinimumSamplesPerUpdate * nominal_interval_s;
  return std::lround(requested_update_interval_s / nominal_interval_s) < kMinimumSamplesPerUpdate
             ? shortest_s
             : requested_update_interval_s;
}

absl::StatusOr<std::unique_ptr<RunCondenser>> RunCondenser::Create(const BenchRun& run, const ErrorModel& pilot,
                                                                   double update_interval_s,
                                                                   double nominal_interval_s,
                                                                   FilterObserver* pilot_observer,
                                                                   const nav::RunCompensations* compensations) {
  if (!(update_interval_s > 0.0)) return absl::InvalidArgumentError("update interval must be positive");
  if (!(nominal_interval_s > 0.0)) return absl::InvalidArgumentError("nominal sample interval must be positive");
  if (run.samples.size() < 2) return absl::InvalidArgumentError("a bench run needs at least two samples");
  if (auto st = ValidateErrorModel(pilot); !st.ok()) return st;
  return std::unique_ptr<RunCondenser>(new RunCondenser(
      std::make_unique<State>(run, pilot, update_interval_s, nominal_interval_s, pilot_observer, compensations)));
}

RunCondenser::RunCondenser(std::unique_ptr<State> state) : state_(std::move(state)) {}
RunCondenser::~RunCondenser() = default;

int RunCondenser::CondenseUpTo(size_t end, bool run_complete) {
  const int before = state_->out.size();
  for (; state_->next_sample < end; ++state_->next_sample) state_->Condense(state_->next_sample, run_complete);
  return state_->out.size() - before;
}

int RunCondenser::Advance() {
  // The motion compensation of interval k reads the reference at k + 1 and k + 2.
  const size_t arrived = state_->run.samples.size();
  return CondenseUpTo(arrived > 2 ? arrived - 2 : 0, false);
}

int RunCondenser::Finish() {
  const int epochs = CondenseUpTo(state_->run.samples.size(), true);
  EpochRun& out = state_->out;
  const BenchRun& run = state_->run;
  out.samples = run.samples.size();
  out.duration_s = run.samples.back().t_s - run.samples.front().t_s + out.sample_interval_s;
  return epochs;
}

const EpochRun& RunCondenser::condensed() const { return state_->out; }

EpochRun RunCondenser::TakeCondensed() { return std::move(state_->out); }

absl::StatusOr<EpochRun> CondenseRun(const BenchRun& run, const ErrorModel& pilot, double update_interval_s,
                                     const nav::RunCompensations* compensations) {
  auto condenser =
      RunCondenser::Create(run, pilot, update_interval_s, run.NominalIntervalS(), nullptr, compensations);
  if (!condenser.ok()) return condenser.status();
  (*condenser)->Finish();
  return (*condenser)->TakeCondensed();
}

}  // namespace insdiag::engine
