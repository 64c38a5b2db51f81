// Forward error-state Kalman filter over a bench run.
//
// The mechanisation (nav/strapdown.h) runs at the sample rate, once per run,
// while the run is condensed to its update epochs (filter/epoch_run.h); the
// filter propagates the error state over each update interval with the
// exact interval transition Φ and noise Q of its model
// (filter/model_transitions.h) and then processes the observation
// channels (observation.h) one by one as scalar updates (seed: channel-wise processing),
// each in Joseph form:
//
//   S = h P hᵀ + r,  ν = z − h x,  K = P hᵀ / S
//   x ← x + K ν
//   P ← (I − K h) P (I − K h)ᵀ + K r Kᵀ  =  P − K (Phᵀ)ᵀ − (Phᵀ) Kᵀ + S K Kᵀ
// (the expanded form keeps Joseph's first-order insensitivity to errors in K
// and is symmetric by construction: the updates of an epoch work on P's
// lower triangle, mirrored once after them). Per channel and epoch it keeps ν,
// α² = S and β² = ν²/α² (seed, monitoring section) and the innovations'
// log-likelihood −½ Σ (ln 2πS + ν²/S).
//
// After the updates the navigation part of the estimate was fed back into
// the mechanisation when the run was condensed (closed loop: attitude,
// velocity, position reset, so that the linearisation stays exact over
// hours); the filter subtracts that known correction u_k from its
// navigation errors, x_nav ← x_nav − u_k. The sensor states keep their
// estimates.
#pragma once

#include <absl/status/statusor.h>

#include <vector>

#include <Eigen/Core>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/filter/epoch_run.h"
#include "insdiag/engine/filter/model_transitions.h"
#include "insdiag/engine/filter/observation.h"
#include "insdiag/engine/model/error_dynamics.h"
#include "insdiag/engine/model/error_model.h"
#include "insdiag/engine/model/state_layout.h"

namespace insdiag::engine {

struct FilterOptions {
  // Interval between observation updates; the run's samples are grouped into
  // intervals of round(update_interval_s / Δt) samples.
  double update_interval_s = 1.0;

  absl::Status Validate() const;
};

// The per-epoch and per-update hooks of the forward pass, for computations
// that must ride along the same pass (the missing-effect score test).
class FilterObserver {
 public:
  virtual ~FilterObserver() = default;
  // After the prior of epoch `index` is formed with `transition` over the interval `epoch`.
  virtual void OnPrediction(int index, const EpochInterval& epoch, const IntervalTransition& transition) = 0;
  // After a scalar update of `channel`: row h, gain K, innovation ν, its variance S.
  virtual void OnScalarUpdate(int channel, const ObservationRow& h, const Eigen::VectorXd& gain,
                              double innovation, double innovation_variance) = 0;
  // After every observed channel of epoch `index` is processed (unobserved
  // channels have no OnScalarUpdate).
  virtual void OnEpochUpdated(int /*index*/, const EpochInterval& /*epoch*/) {}
};

// Several observers riding one pass, each called in turn (null ones skipped).
class FilterObservers final : public FilterObserver {
 public:
  explicit FilterObservers(std::vector<FilterObserver*> observers) : observers_(std::move(observers)) {
    std::erase(observers_, nullptr);
  }
  void OnPrediction(int index, const EpochInterval& epoch, const IntervalTransition& transition) override {
    for (FilterObserver* o : observers_) o->OnPrediction(index, epoch, transition);
  }
  void OnScalarUpdate(int channel, const ObservationRow& h, const Eigen::VectorXd& gain, double innovation,
                      double innovation_variance) override {
    for (FilterObserver* o : observers_) o->OnScalarUpdate(channel, h, gain, innovation, innovation_variance);
  }
  void OnEpochUpdated(int index, const EpochInterval& epoch) override {
    for (FilterObserver* o : observers_) o->OnEpochUpdated(index, epoch);
  }

 private:
  std::vector<FilterObserver*> observers_;
};

// Upper triangle of a symmetric n×n matrix, row by row.
int PackedSize(int n);
void PackSymmetric(const Eigen::MatrixXd& P, double* out);
void UnpackSymmetric(const double* in, int n, Eigen::MatrixXd& P);

// One packed covariance per row (row-major so that a row is contiguous).
using PackedCovariances = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;


// A pass's transitions Φ_k, kept for the smoother and the scans: A_k and B_k
// in storage reserved once per pass, and each distinct D once (an interval's
// D depends on its length alone), so that recording an epoch allocates
// nothing.
class StoredTransitions {
 public:
  void Reserve(size_t epochs, int sensor_states);
  void Append(const StateTransition& t);
  size_t size() const { return A_.size(); }
  // Φ_k: from epoch k−1 (or the start) to k.
  TransitionView operator[](size_t k) const;
  double Bytes() const;

 private:
  int sensor_states_ = 0;
  std::vector<Matrix9d> A_;
  std::vector<double> B_;  // B_k column-major, 9 × m each
  std::vector<SensorBlocks> distinct_D_;
  std::vector<int> D_of_epoch_;
};

struct ForwardPass {
  int state_size = 0;
  // Epoch k: the update at time epoch_time_s[k] (k = 0 … K−1).
  std::vector<double> epoch_time_s;
  std::vector<double> epoch_start_s;  // the start of the epoch's update interval
  std::vector<int> epoch_sample;  // index of the run's sample at each epoch
  // K × kChannelCount; a channel not observed at an epoch (the attitude
  // while the table turns, observation.h) has ν = α² = r = 0 there.
  Eigen::MatrixXd z;                    // observations
  Eigen::MatrixXd innovation;           // ν
  Eigen::MatrixXd innovation_variance;  // α²
  Eigen::MatrixXd observation_noise;    // r
  Eigen::MatrixXd x_pred, x_filt;       // K × n, before and after the epoch's updates (before the reset)
  PackedCovariances P_pred, P_filt;     // K × PackedSize(n)
  StoredTransitions transitions;  // transitions[k]: from epoch k−1 (or the start) to k (kept for the smoother)
  Eigen::VectorXd x0;
  Eigen::MatrixXd P0;
  double log_likelihood = 0.0;
  int scalar_updates = 0;
  double duration_s = 0.0;

  int epochs() const { return static_cast<int>(epoch_time_s.size()); }
  // Channel c was observed at epoch k.
  bool Observed(int k, int c) const { return innovation_variance(k, c) > 0.0; }
  // Bytes held per run sample, for the memory figure in docs/PERFORMANCE.md.
  double BytesPerSample(size_t samples) const;
};

// The forward filter of one model stepped epoch by epoch over a condensed run.
class EpochFilter {
 public:
  // `model`, `layout` and `run` must outlive the filter.
  EpochFilter(const ErrorModel& model, const StateLayout& layout, const EpochRun& run);

  // Predicts over epoch `index`'s interval and processes its observations;
  // records the epoch into `pass` when given.
  void Step(int index, ForwardPass* pass, FilterObserver* observer);
  // The mechanisation was corrected by `u` after the step: x_nav ← x_nav − u.
  void ApplyFeedback(const NavigationVector& u);
  // The navigation errors' estimate after the last step's updates, before the feedback.
  const NavigationVector& navigation_estimate() const { return navigation_estimate_; }
  double log_likelihood() const { return log_likelihood_; }
  int scalar_updates() const { return scalar_updates_; }
  const Eigen::VectorXd& x() const { return x_; }
  const Eigen::MatrixXd& P() const { return P_; }

 private:
  const ErrorModel& model_;
  const EpochRun& run_;
  ModelTransitions transitions_;
  using ObservationNoise = std::array<double, kChannelCount>;
  // r of every channel at epoch `e` (the reference's accuracy and the sensors' quantisation).
  ObservationNoise ObservationNoiseAt(const EpochInterval& e) const;

  std::array<ObservationRow, kChannelCount> rows_;
  Eigen::VectorXd x_;
  Eigen::MatrixXd P_;
  Eigen::VectorXd PH_, gain_, half_joseph_;
  NavigationVector navigation_estimate_ = NavigationVector::Zero();
  double log_likelihood_ = 0.0;
  int scalar_updates_ = 0;
};

// The forward filter of `model` over a condensed run.
absl::StatusOr<ForwardPass> RunForwardFilter(const EpochRun& run, const ErrorModel& model,
                                             FilterObserver* observer = nullptr);

// Condenses `run` with `model` as its own pilot, then filters it: the
// feedback is the model's own estimate.
absl::StatusOr<ForwardPass> RunForwardFilter(const BenchRun& run, const ErrorModel& model,
                                             const FilterOptions& options, FilterObserver* observer = nullptr);

// The filter's initial covariance for a model and a run: the reference's
// accuracy for the navigation errors — the initial attitude's as the run
// states it (level and heading), else the encoders', with the counters'
// unknown residue at the start (quantisation) — and steady-state or prior
// variances for the sensor states.
Eigen::MatrixXd InitialCovariance(const ErrorModel& model, const StateLayout& layout, const EpochRun& run);

// The 1σ of a heading the bench did not survey: what gyro-compassing the
// run's start tells, a horizontal gyro bias b turning it by b / (Ω cos L)
// (coarse_alignment.h), with b the model's largest gyro drift σ; no more
// than kUnsurveyedHeadingLimitRad, within which the phi-angle model of the
// heading error still holds: its Earth-rate error 2Ω_h sin(ψ/2) is Ω_h ψ
// within 4 % at 1 rad. A heading the run cannot tell is then carried as a
// horizontal rate error of at most Ω cos L, below any such gyro's bias.
inline constexpr double kUnsurveyedHeadingLimitRad = 1.0;
double UnsurveyedHeadingSigmaRad(const ErrorModel& model, const Site& site);

}  // namespace insdiag::engine
