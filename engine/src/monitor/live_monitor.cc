#include "insdiag/engine/monitor/live_monitor.h"

#include <algorithm>
#include <cmath>
#include <span>

#include "insdiag/engine/model/state_layout.h"

namespace insdiag::engine {

absl::Status LiveMonitorOptions::Validate() const {
  if (!(update_interval_s > 0.0)) return absl::InvalidArgumentError("update interval must be positive");
  if (!(planned_duration_s > 0.0)) return absl::InvalidArgumentError("the planned duration must be positive");
  if (nominal_interval_samples < 1) return absl::InvalidArgumentError("nominal_interval_samples must be ≥ 1");
  return absl::OkStatus();
}

absl::StatusOr<std::unique_ptr<LiveMonitor>> LiveMonitor::Create(const BenchRun& run, const ErrorModel& model,
                                                                  const LiveMonitorOptions& options) {
  if (auto st = options.Validate(); !st.ok()) return st;
  if (auto st = ValidateErrorModel(model); !st.ok()) return st;
  return std::unique_ptr<LiveMonitor>(new LiveMonitor(run, model, options));
}

LiveMonitor::LiveMonitor(const BenchRun& run, const ErrorModel& model, const LiveMonitorOptions& options)
    : run_(run), model_(model), options_(options) {}

absl::Status LiveMonitor::StartCondensing() {
  const auto first = std::min(run_.samples.size(), static_cast<size_t>(options_.nominal_interval_samples) + 1);
  const double nominal_interval_s = MedianSampleIntervalS(std::span(run_.samples).first(first));
  auto condenser = RunCondenser::Create(run_, model_, options_.update_interval_s, nominal_interval_s, this);
  if (!condenser.ok()) return condenser.status();
  condenser_ = *std::move(condenser);
  const double epoch_interval_s = condenser_->condensed().samples_per_epoch * nominal_interval_s;
  planned_epochs_ = std::max(1, static_cast<int>(std::ceil(options_.planned_duration_s / epoch_interval_s - 1e-9)));
  tests_.emplace(planned_epochs_, epoch_interval_s, options_.monitor);
  steps_.emplace(StateLayout(model_).size(), planned_epochs_, epoch_interval_s, options_.steps);
  return absl::OkStatus();
}

absl::StatusOr<int> LiveMonitor::Advance() {
  if (condenser_ == nullptr) {
    if (run_.samples.size() <= static_cast<size_t>(options_.nominal_interval_samples)) return 0;
    if (auto st = StartCondensing(); !st.ok()) return st;
  }
  return condenser_->Advance();
}

absl::StatusOr<int> LiveMonitor::Finish() {
  if (condenser_ == nullptr) {
    if (run_.samples.size() < 2) return absl::InvalidArgumentError("a bench run needs at least two samples");
    if (auto st = StartCondensing(); !st.ok()) return st;
  }
  return condenser_->Finish();
}

void LiveMonitor::OnPrediction(int /*index*/, const EpochInterval& epoch, const IntervalTransition& transition) {
  steps_->OnPrediction(epoch, transition);
  epoch_start_s_ = epoch.start_s;
  epoch_time_s_ = epoch.time_s;
  // A channel the epoch does not observe keeps ν = α² = 0 (InnovationTests).
  innovation_.fill(0.0);
  innovation_variance_.fill(0.0);
}

void LiveMonitor::OnScalarUpdate(int channel, const ObservationRow& h, const Eigen::VectorXd& gain,
                                 double innovation, double innovation_variance) {
  steps_->OnScalarUpdate(h, gain, innovation, innovation_variance);
  innovation_[static_cast<size_t>(channel)] = innovation;
  innovation_variance_[static_cast<size_t>(channel)] = innovation_variance;
  nis_sum_ += innovation * innovation / innovation_variance;
  ++updates_;
}

void LiveMonitor::OnEpochUpdated(int /*index*/, const EpochInterval& /*epoch*/) {
  tests_->Add(epoch_start_s_, epoch_time_s_, innovation_, innovation_variance_);
  steps_->CloseEpoch(epoch_time_s_);
}

LiveStatus LiveMonitor::Status() const {
  LiveStatus out;
  out.samples = run_.samples.size();
  out.planned_epochs = planned_epochs_;
  if (!tests_) return out;
  const InnovationTests& tests = *tests_;
  out.epochs = tests.epochs();
  out.time_s = epoch_time_s_;
  out.beta2 = tests.beta2();
  out.window_ratio = tests.window_ratio();
  out.faults = tests.faults();
  out.faults.insert(out.faults.end(), steps_->steps().begin(), steps_->steps().end());
  SortFaultIntervals(out.faults);
  out.nis_mean = updates_ > 0 ? nis_sum_ / updates_ : 0.0;
  const MeanNisBand nis_band = MeanNisBandOf(updates_, options_.monitor.family_wise_alpha);
  out.nis_band_low = nis_band.low;
  out.nis_band_high = nis_band.high;
  out.gamma2 = tests.gamma2();
  out.eta2 = tests.eta2();
  out.outlier_threshold = tests.outlier_threshold();
  out.gradual_threshold = tests.gradual_threshold();
  out.step_statistic = steps_->largest_statistic();
  out.step_threshold = steps_->threshold();
  out.verdict = VerdictOf(tests.gradual_found() || !steps_->steps().empty(), !out.faults.empty(),
                          nis_band.Excludes(out.nis_mean));
  return out;
}

}  // namespace insdiag::engine
