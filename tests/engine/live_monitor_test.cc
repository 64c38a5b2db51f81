// Monitoring a test while it is recorded (monitor/live_monitor.h): the
// samples arrive in chunks of random size, and what the live monitor shows
// must be what the monitor of the completed run's forward pass finds, and
// show a bias step soon after its onset.
#include <gtest/gtest.h>

#include <absl/strings/str_format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
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

    // The innovation tests' intervals; the step scan's (ABRUPT) are the live monitor's own.
    std::vector<FaultInterval> shown;
    for (const FaultInterval& f : live.final_status.faults) {
      if (f.kind != FaultKind::kAbrupt) shown.push_back(f);
    }
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
    EXPECT_EQ(live.final_status.verdict, Verdict::kFaulty);
    EXPECT_EQ(post.verdict, Verdict::kFaulty);
    EXPECT_NEAR(live.final_status.nis_mean, post.nis_mean, 1e-9 * post.nis_mean);
  }
}

// The table held still for `duration_s`, turned to `outer_deg` (yaw) and
// tilted to `inner_deg` about the inner axis.
sim::TableProfile StillAt(double outer_deg, double inner_deg, double duration_s) {
  sim::TableProfile p;
  p.name = "still";
  p.angular_acceleration_rad_s2 = 10.0 * testing::kDeg;
  p.initial_outer_rad = outer_deg * testing::kDeg;
  p.initial_inner_rad = inner_deg * testing::kDeg;
  p.thermal.ambient_degc = 25.0;
  p.segments = {{sim::TableSegment::Kind::kHold, duration_s, 0, 0, 0}};
  return p;
}

struct StepCase {
  sim::SimulatedUnit unit;
  sim::TableProfile profile;
  double rate_hz = 50.0;
  double onset_s = 0.0;
  std::string channel;  // the stepped sensor channel, "gyro_x" …
  std::string label;
};

struct SweepOutcome {
  std::vector<double> delays_s;  // from the onset to the first interval shown
  int shown_in_time = 0;         // within 60 s of the onset
  int named_right = 0;           // a bias step named on the stepped channel, from within 60 s of the onset
  std::string failures;
};

// Runs each case live.
SweepOutcome RunLive(const std::vector<StepCase>& cases) {
  SweepOutcome out;
  for (size_t i = 0; i < cases.size(); ++i) {
    const StepCase& c = cases[i];
    const auto sim = testing::SimulateOrDie(c.unit, c.profile, c.rate_hz, 500 + i);
    LiveMonitorOptions options;
    options.planned_duration_s = sim.run.DurationS();
    const LiveOutcome live = MonitorLive(sim.run, testing::TrueBaseModel(c.unit), options, c.onset_s, 60 + i, 200);
    const double delay_s = live.first_shown_s - c.onset_s;
    out.delays_s.push_back(delay_s);
    if (delay_s <= 60.0) {
      ++out.shown_in_time;
    } else {
      out.failures += absl::StrFormat(" [%s: delay %.0f s]", c.label, delay_s);
    }
    const auto& faults = live.final_status.faults;
    const bool named = std::any_of(faults.begin(), faults.end(), [&](const FaultInterval& f) {
      return f.kind == FaultKind::kAbrupt && f.channel == c.channel && std::abs(f.start_s - c.onset_s) <= 60.0;
    });
    if (named) {
      ++out.named_right;
    } else {
      out.failures += absl::StrFormat(" [%s: no step named on %s]", c.label, c.channel);
    }
  }
  std::vector<double> sorted = out.delays_s;
  std::sort(sorted.begin(), sorted.end());
  std::printf("delays from the onset [s]: median %.0f, max %.0f; steps named on their channel: %d of %zu\n",
              sorted[sorted.size() / 2], sorted.back(), out.named_right, sorted.size());
  return out;
}

// An accelerometer bias step of five drift σ, on a random axis, sign,
// onset, rate and unit class, the table turning before and still after.
TEST(LiveMonitorSweep, ShowsAnAccelerometerStepOfFiveDriftSigmaWithinAMinute) {
  std::mt19937_64 rng(2026);
  std::vector<StepCase> cases;
  for (int i = 0; i < 12; ++i) {
    StepCase c;
    c.unit = i % 2 == 0 ? testing::NavigationGradeUnit() : TacticalUnit();
    const int axis = static_cast<int>(rng() % 3);
    c.onset_s = std::uniform_real_distribution<double>(420.0, 800.0)(rng);
    const double sign = rng() % 2 == 0 ? 1.0 : -1.0;
    c.unit.bias_steps.push_back(
        {Sensor::kAccelerometer, axis, c.onset_s, sign * 5.0 * c.unit.acc.bias[static_cast<size_t>(axis)].sigma});
    c.profile = testing::ShortTurnsProfile(60.0, 1000.0);
    c.rate_hz = std::array{10.0, 50.0, 100.0}[static_cast<size_t>(i % 3)];
    c.label = absl::StrFormat("acc %c at %.0f s, %g Hz", "xyz"[axis], c.onset_s, c.rate_hz);
    c.channel = std::string("acc_") + "xyz"[axis];
    cases.push_back(std::move(c));
  }
  const SweepOutcome outcome = RunLive(cases);
  EXPECT_GE(outcome.shown_in_time, 11) << outcome.failures;
  EXPECT_GE(outcome.named_right, 10) << outcome.failures;
}

// A gyro whose drift jumps by 1 °/h (a failing DTG: a hundred times a
// navigation-grade drift σ, ten times a tactical one), on a random axis,
// with the table still at a random heading and the gyro out of the
// vertical. A vertical gyro's step only turns the heading, which shows
// through the Earth's rate in minutes, not seconds (docs/LIVE.md).
TEST(LiveMonitorSweep, ShowsAGyroStepOfOneDegreePerHourWithinAMinute) {
  std::mt19937_64 rng(2027);
  std::vector<StepCase> cases;
  for (int i = 0; i < 12; ++i) {
    StepCase c;
    c.unit = i % 2 == 0 ? testing::NavigationGradeUnit() : TacticalUnit();
    const int axis = static_cast<int>(rng() % 3);
    c.onset_s = std::uniform_real_distribution<double>(300.0, 600.0)(rng);
    const double sign = rng() % 2 == 0 ? 1.0 : -1.0;
    c.unit.bias_steps.push_back({Sensor::kGyro, axis, c.onset_s, sign * 1.0 * testing::kDegPerHour});
    const double heading_deg = std::uniform_real_distribution<double>(0.0, 360.0)(rng);
    // At inner 0° body z is vertical; at 90° body x is.
    const double inner_deg = axis == 2 ? 90.0 : (axis == 0 ? 0.0 : (rng() % 2 == 0 ? 0.0 : 90.0));
    c.profile = StillAt(heading_deg, inner_deg, 800.0);
    c.rate_hz = std::array{10.0, 50.0, 100.0}[static_cast<size_t>(i % 3)];
    c.label = absl::StrFormat("gyro %c at %.0f s, heading %.0f°, %g Hz", "xyz"[axis], c.onset_s, heading_deg,
                              c.rate_hz);
    c.channel = std::string("gyro_") + "xyz"[axis];
    cases.push_back(std::move(c));
  }
  const SweepOutcome outcome = RunLive(cases);
  EXPECT_GE(outcome.shown_in_time, 11) << outcome.failures;
  EXPECT_GE(outcome.named_right, 10) << outcome.failures;
}

// Healthy units, turning and still, at 10, 50 and 100 Hz: the live verdict
// is FAULTY at most at the family-wise level.
TEST(LiveMonitorSweep, HealthyUnitsAreNotCalledFaulty) {
  int faulty = 0;
  std::string which;
  for (int i = 0; i < 12; ++i) {
    const sim::SimulatedUnit unit = i % 2 == 0 ? testing::NavigationGradeUnit() : TacticalUnit();
    const double rate_hz = std::array{10.0, 50.0, 100.0}[static_cast<size_t>(i % 3)];
    const auto sim = testing::SimulateOrDie(unit, testing::ShortTurnsProfile(60.0, 1200.0), rate_hz, 900 + i);
    LiveMonitorOptions options;
    options.planned_duration_s = sim.run.DurationS();
    const LiveOutcome live = MonitorLive(sim.run, testing::TrueBaseModel(unit), options, 0.0, 80 + i, 300);
    if (live.final_status.verdict == Verdict::kFaulty) {
      ++faulty;
      which += absl::StrFormat(" [seed %d, %g Hz: %s on %s]", 900 + i, rate_hz,
                               FaultKindName(live.final_status.faults.front().kind),
                               live.final_status.faults.front().channel);
    }
  }
  EXPECT_LE(faulty, 1) << which;
}

}  // namespace
}  // namespace insdiag::engine
