// Monitoring a test while it is recorded (monitor/live_monitor.h): the
// samples arrive in chunks of random size, and what the live monitor shows
// must be what the monitor of the completed run's forward pass finds, and
// show a bias step soon after its onset.
#include <gtest/gtest.h>

#include <absl/strings/str_format.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "insdiag/engine/filter/forward_filter.h"
#include "insdiag/engine/filter/smoother.h"
#include "insdiag/engine/monitor/live_monitor.h"
#include "scenarios.h"

namespace insdiag::engine {
namespace {

// A tactical unit: gyro drift 0.1 °/h with τ 200 s, ARW 0.01 °/√h;
// accelerometer bias 50 µg with τ 300 s, VRW 20 µg/√Hz.
sim::SimulatedUnit TacticalUnit() {
  sim::SimulatedUnit u = testing::NavigationGradeUnit();
  u.serial = "SIM-TAC";
  u.type.clear();
  for (int i = 0; i < 3; ++i) {
    u.gyro.bias[static_cast<size_t>(i)] = {0.1 * testing::kDegPerHour, 200.0};
    u.acc.bias[static_cast<size_t>(i)] = {50.0 * testing::kMicroG, 300.0};
  }
  u.gyro.white_noise_density.setConstant(0.01 * testing::kDeg / 60.0);
  u.acc.white_noise_density.setConstant(20.0 * testing::kMicroG);
  return u;
}

struct LiveOutcome {
  LiveStatus final_status;
  // The time of the first epoch whose status showed an interval ending at or
  // after `watch_from_s`; NaN if none did.
  double first_shown_s = std::nan("");
};

// Feeds `run`'s samples to a live monitor in chunks of 1 … max_chunk samples.
LiveOutcome MonitorLive(const BenchRun& run, const ErrorModel& model, const LiveMonitorOptions& options,
                        double watch_from_s, uint64_t seed, int max_chunk) {
  BenchRun growing;
  growing.metadata = run.metadata;
  growing.has_temperature = run.has_temperature;
  growing.samples.reserve(run.samples.size());
  auto live = LiveMonitor::Create(growing, model, options);
  EXPECT_TRUE(live.ok()) << live.status();
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> chunk(1, max_chunk);
  LiveOutcome out;
  size_t next = 0;
  while (next < run.samples.size()) {
    const size_t end = std::min(run.samples.size(), next + static_cast<size_t>(chunk(rng)));
    growing.samples.insert(growing.samples.end(), run.samples.begin() + static_cast<long>(next),
                           run.samples.begin() + static_cast<long>(end));
    next = end;
    auto epochs = (*live)->Advance();
    EXPECT_TRUE(epochs.ok()) << epochs.status();
    if (std::isnan(out.first_shown_s) && *epochs > 0) {
      const LiveStatus status = (*live)->Status();
      for (const FaultInterval& f : status.faults) {
        if (f.end_s >= watch_from_s) out.first_shown_s = status.time_s;
      }
    }
  }
  EXPECT_TRUE((*live)->Finish().ok());
  out.final_status = (*live)->Status();
  return out;
}

MonitorResult MonitorOfCompletedRun(const BenchRun& run, const ErrorModel& model) {
  auto fw = RunForwardFilter(run, model, FilterOptions{});
  EXPECT_TRUE(fw.ok()) << fw.status();
  auto sm = RunSmoother(*fw);
  EXPECT_TRUE(sm.ok()) << sm.status();
  return Monitor(*fw, *sm, StateLayout(model), {}, MonitorOptions{});
}

TEST(LiveMonitor, ShowsWhatTheCompletedRunsForwardPassShows) {
  for (const double rate_hz : {10.0, 50.0}) {
    sim::SimulatedUnit unit = TacticalUnit();
    unit.bias_steps.push_back({Sensor::kAccelerometer, 1, 400.0, 5.0 * unit.acc.bias[1].sigma});
    unit.bias_steps.push_back({Sensor::kGyro, 0, 620.0, 5.0 * unit.gyro.bias[0].sigma});
    const auto sim = testing::SimulateOrDie(unit, testing::ShortTurnsProfile(60.0, 900.0), rate_hz, 31);
    const ErrorModel model = testing::TrueBaseModel(unit);
    LiveMonitorOptions options;
    options.planned_duration_s = sim.run.DurationS();
    const LiveOutcome live = MonitorLive(sim.run, model, options, 0.0, 7, 400);
    const MonitorResult post = MonitorOfCompletedRun(sim.run, model);

    const auto& shown = live.final_status.faults;
    ASSERT_FALSE(shown.empty()) << "the steps show no interval at " << rate_hz << " Hz";
    ASSERT_EQ(shown.size(), post.faults.size()) << rate_hz << " Hz";
    for (size_t i = 0; i < shown.size(); ++i) {
      SCOPED_TRACE(absl::StrFormat("%g Hz, interval %d", rate_hz, i));
      EXPECT_EQ(shown[i].channel, post.faults[i].channel);
      EXPECT_EQ(shown[i].kind, post.faults[i].kind);
      EXPECT_NEAR(shown[i].start_s, post.faults[i].start_s, 1e-6);
      EXPECT_NEAR(shown[i].end_s, post.faults[i].end_s, 1e-6);
      EXPECT_NEAR(shown[i].peak_statistic, post.faults[i].peak_statistic, 1e-6 * post.faults[i].peak_statistic);
    }
    EXPECT_EQ(live.final_status.epochs, static_cast<int>(post.window_ratio.rows()));
    EXPECT_EQ(live.final_status.verdict, post.verdict);
    EXPECT_NEAR(live.final_status.nis_mean, post.nis_mean, 1e-9 * post.nis_mean);
  }
}

// A bias step of five drift σ on a random sensor axis at a random onset, at
// 10, 50 or 100 Hz: the live monitor must show it within 60 s of its onset.
TEST(LiveMonitorSweep, ShowsABiasStepWithinAMinuteOfItsOnset) {
  constexpr int kRuns = 12;
  std::mt19937_64 rng(2026);
  int shown_in_time = 0;
  std::string failures;
  for (int i = 0; i < kRuns; ++i) {
    sim::SimulatedUnit unit = TacticalUnit();
    const Sensor sensor = i % 2 == 0 ? Sensor::kGyro : Sensor::kAccelerometer;
    const int axis = static_cast<int>(rng() % 3);
    const double onset_s = std::uniform_real_distribution<double>(300.0, 700.0)(rng);
    const double sign = rng() % 2 == 0 ? 1.0 : -1.0;
    const auto& bias = (sensor == Sensor::kGyro ? unit.gyro : unit.acc).bias[static_cast<size_t>(axis)];
    unit.bias_steps.push_back({sensor, axis, onset_s, sign * 5.0 * bias.sigma});
    const double rate_hz = std::array{10.0, 50.0, 100.0}[static_cast<size_t>(i % 3)];
    const auto sim = testing::SimulateOrDie(unit, testing::ShortTurnsProfile(60.0, 1000.0), rate_hz, 100 + i);
    LiveMonitorOptions options;
    options.planned_duration_s = sim.run.DurationS();
    const LiveOutcome live = MonitorLive(sim.run, testing::TrueBaseModel(unit), options, onset_s, 40 + i, 200);
    const double delay_s = live.first_shown_s - onset_s;
    if (delay_s <= 60.0) {
      ++shown_in_time;
    } else {
      failures += absl::StrFormat(" [%s %c at %.0f s, %g Hz: delay %.0f s]",
                                  sensor == Sensor::kGyro ? "gyro" : "acc", "xyz"[axis], onset_s, rate_hz, delay_s);
    }
  }
  EXPECT_GE(shown_in_time, kRuns - 1) << failures;
}

}  // namespace
}  // namespace insdiag::engine
