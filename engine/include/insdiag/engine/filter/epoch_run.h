// The run condensed to the filter's update epochs: everything the error-state
// filter needs from the samples, computed once per run so that every filter
// pass of an analysis — identification, structure tests, model B, discovery —
// costs the epochs only, not the samples.
//
// One sweep over the samples (CondenseRun) runs the strapdown mechanisation
// (nav/strapdown.h, the table's reference motion for the intra-sample
// compensation, nav/table_motion.h) and condenses each update interval's
// samples j = 1 … M into, in interval-end coordinates (error_dynamics.h):
//
//   A = T_M                                      navigation transition over the interval
//   μ_p[:, a] = Σ_j b_j,a s_j^p,  p = 0, 1, 2     coupling moments of sensor axis a
//   W_a = Σ_j b_j,a b_j,aᵀ / Δt_j                 white noise of axis a per unit density²
//   Q_a = Σ_j c_j,a c_j,aᵀ Δt_j²                  accelerometer quantisation (c: to position)
//   K[:, i] = Σ_j b_j r_i(u_j)                    every constant catalogue parameter's input
//
// b_j,a = T_M T_j⁻¹ Γ [−C_b^n | C_b^n]_a is how a unit error held on sensor
// axis a over sample j reaches the navigation errors at the epoch, s_j = t_{j−1}
// − t_start the sample's start within the interval, r_i the catalogue
// regressor of the sample's inputs u_j. The filter builds each model's
// interval transition from these (ModelIntervalTransition below):
//
// * A constant effect's column is K[:, i], exactly.
// * A sensor state that decays or wanders within the interval (a Gauss–Markov
//   drift, a walk, a second-order pair, per-sample transition d) needs
//   Σ_j b_j d^{j−1} and the double sums of its process noise. The coupling is
//   reconstructed as the quadratic in s that has the moments μ_0 … μ_2
//   (b_j ≈ Σ_p c_p s_j^p, c = μ S⁻¹ with S_pq = Σ_j s_j^{p+q}), and the sums
//   over the sample grid are taken exactly for it:
//     B = Σ_p c_p w_p,      w_p = Σ_j s_j^p d^{j−1}
//     Q_ns = q Σ_p c_p v_p, Q_nn += q Σ_pr c_p c_rᵀ U_pr   (the noise injected within the interval)
//   with a_p,i = Σ_{j>i} s_j^p d^{j−1−i}, v_p = Σ_i a_p,i (d^{M−i})ᵀ, U_pr = Σ_i a_p,i a_r,iᵀ.
//   Exact when the coupling is quadratic within the interval; the residual of
//   the fit is orthogonal to 1, s and s², so for a state that decays slowly
//   (d^{j−1} ≈ 1 − λ s_j + …) the error is of third order in λΔt; for a fast
//   one it is the coupling's cubic part, ≈ (ω Δt)³/6 of it when the table
//   turns at ω (8e-4 at 10 °/s over a one-second interval).
// * White sensor noise and quantisation are exact: Q_nn += Σ_a N_a² W_a + Q_acc,a² Q_a.
//
// The mechanisation is corrected after each epoch's updates by the estimate
// of a pilot model's filter (closed loop, so that the linearisation stays
// exact over hours: forward_filter.h). Every later pass treats these
// corrections as known inputs u_k (x_nav ← x_nav − u_k): in the linear error
// model its innovations are those it would have had with its own feedback.
#pragma once

#include <absl/status/statusor.h>

#include <array>
#include <memory>
#include <numbers>
#include <vector>

#include <Eigen/Core>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/filter/observation.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/model/error_dynamics.h"
#include "insdiag/engine/model/error_model.h"
#include "insdiag/engine/nav/table_motion.h"

namespace insdiag::engine {

// The six sensor axes in this order: gyro x, y, z, accelerometer x, y, z.
inline constexpr int kSensorAxisCount = 6;
inline int SensorAxisIndex(Sensor sensor, int axis) { return (sensor == Sensor::kGyro ? 0 : 3) + axis; }

// Coupling moments μ_p, p = 0 … kCouplingDegree.
inline constexpr int kCouplingDegree = 2;
inline constexpr int kCouplingMoments = kCouplingDegree + 1;

using Matrix96d = Eigen::Matrix<double, kNavigationStates, kSensorAxisCount>;
using PackedSymmetric9d = Eigen::Matrix<double, 45, 1>;

// One update interval of the run, condensed (header).
struct EpochInterval {
  double time_s = 0.0;   // the epoch: the interval's end, where the observations are taken
  double start_s = 0.0;  // the interval's start
  int sample = 0;        // the run's sample at the epoch
  int samples = 0;       // M
  double sample_interval_s = 0.0;  // Δt of its samples (their mean, if irregular)
  Matrix9d A;
  std::array<Matrix96d, kCouplingMoments> moments;      // μ_p
  Eigen::Matrix<double, kCouplingMoments, kCouplingMoments> gram;  // S
  std::array<PackedSymmetric9d, kSensorAxisCount> white;  // W_a (gyro axes, then accelerometer)
  std::array<PackedSymmetric9d, 3> quantisation;          // Q_a of the accelerometer axes
  Eigen::Matrix<double, kNavigationStates, Eigen::Dynamic>
      constants;  // K, columns as EpochRun::constant_columns
  std::array<double, kChannelCount> z{};                  // observations (observation.h) at the epoch
  // The table stood still over the interval and its encoders are read
  // (bench_run.h): the attitude channels are observed at the epoch.
  bool attitude_observed = false;
  NavigationVector feedback = NavigationVector::Zero();   // u_k
  Eigen::Matrix3d C_b_n = Eigen::Matrix3d::Identity();    // reference attitude at the epoch
  // The interval is the first of a segment after the first (bench_run.h):
  // the mechanisation started again at its start, from the segment's
  // reference, and the navigation errors start again from the reference's
  // accuracy, independent of everything before (ModelTransitions::Build).
  bool starts_segment = false;
};

struct EpochRun {
  Site site;
  // What the run says of its initial attitude's accuracy (bench_run.h): the
  // filter's initial attitude covariance.
  StatedAttitudeAccuracy stated_attitude;
  double update_interval_s = 0.0;
  double sample_interval_s = 0.0;  // the run's nominal Δt
  int samples_per_epoch = 0;
  size_t samples = 0;
  double duration_s = 0.0;
  // The columns of EpochInterval::constants: every parameter of every
  // constant catalogue term.
  std::vector<ConstantParameter> constant_columns;
  std::vector<EpochInterval> epochs;

  int size() const { return static_cast<int>(epochs.size()); }
  // Column of a constant parameter in EpochInterval::constants, −1 if none.
  int ConstantColumn(const EffectTerm& term, int parameter) const;
  double BytesPerEpoch() const;
};

// The update interval a run is filtered at: the one asked for, lengthened to
// two samples where it holds fewer. With one sample an interval the
// mechanisation's position step is ½Δt times its velocity step (the
// trapezoid, nav/strapdown.h), so against the bench's exact reference (the
// surveyed site, zero velocity) the position and velocity innovations are
// multiples of one another: the six channels carry three dimensions, and the
// NIS counts half its degrees of freedom (a healthy 1 Hz run read 0.43;
// docs/FAULT_SCENARIOS.md, "A unit sampled at 1 or 2 Hz").
inline constexpr int kMinimumSamplesPerUpdate = 2;
double UpdateIntervalForRun(double requested_update_interval_s, double nominal_interval_s);

// Condenses `run` with `pilot` correcting the mechanisation, every
// UpdateIntervalForRun. Needs at least two samples and a valid model (σ ≥ 0,
// τ > 0 where σ > 0). `compensations`:
// the run's motion compensations when the caller has them (else computed
// sample by sample).
absl::StatusOr<EpochRun> CondenseRun(const BenchRun& run, const ErrorModel& pilot, double update_interval_s,
                                     const nav::RunCompensations* compensations = nullptr);

class FilterObserver;

// The condensation of a run whose samples may still be arriving (a test
// being recorded): CondenseRun is this over a complete run. Advance condenses
// every sample whose interval's motion compensation has the samples it reads
// (the two after it, nav/table_motion.h), so that each epoch comes out exactly
// as CondenseRun makes it from the whole run; Finish condenses the rest once
// the run is complete. The pilot's filter, stepped at each epoch, is the
// model's own forward pass (forward_filter.h): `pilot_observer` sees its
// updates as they happen.
class RunCondenser {
 public:
  // `run` must hold at least two samples and outlive the condenser; its
  // samples may be appended to between calls, its metadata must not change.
  // `nominal_interval_s`: the run's nominal Δt (BenchRun::NominalIntervalS
  // of the complete run, or of the samples so far while it arrives).
  // `compensations`: the complete run's (CondenseRun), else null.
  static absl::StatusOr<std::unique_ptr<RunCondenser>> Create(const BenchRun& run, const ErrorModel& pilot,
                                                              double update_interval_s, double nominal_interval_s,
                                                              FilterObserver* pilot_observer = nullptr,
                                                              const nav::RunCompensations* compensations = nullptr);
  ~RunCondenser();

  // Condenses what the samples so far allow; returns the epochs completed by this call.
  int Advance();
  // The run is complete: condenses its remaining samples (the last epoch may be short).
  int Finish();

  const EpochRun& condensed() const;
  // The condensed run, once finished; the condenser is spent.
  EpochRun TakeCondensed();

 private:
  struct State;
  explicit RunCondenser(std::unique_ptr<State> state);
  int CondenseUpTo(size_t end, bool run_complete);

  std::unique_ptr<State> state_;
};

// The table stands still over an interval when every reference angle of its
// samples stays within this many readout σ of the angle at its start (a
// difference of two readouts has σ√2: 5√2σ is a five-σ excursion of it).
inline constexpr double kStillToleranceReadoutSigmas = 5.0 * std::numbers::sqrt2;
double StillToleranceRad(const ReferenceAccuracy& reference);

// A packed symmetric 9×9 (upper triangle, row by row) unpacked, and back.
Matrix9d Unpack9(const PackedSymmetric9d& packed);
PackedSymmetric9d Pack9(const Matrix9d& m);

}  // namespace insdiag::engine
