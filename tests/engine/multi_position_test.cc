// A multi-position test: six static positions and three turns recorded as
// separate files with unrecorded moves between them, joined into one run of
// segments (bench_run.h). The joint analysis aligns each segment anew and
// shares the sensor errors, so that it recovers what no single position
// tells: the accelerometer scale factors and biases and the gyro biases,
// within 3 standard errors. The same effects on one level static file alone
// are reported as not observable.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include <absl/strings/str_format.h>

#include "insdiag/engine/analysis.h"
#include "insdiag/engine/nav/rotation.h"
#include "insdiag/engine/sim/simulator.h"
#include "scenarios.h"

namespace insdiag::engine::testing {
namespace {

constexpr double kRateHz = 10.0;
constexpr double kHoldS = 300.0;
constexpr double kTableRateRadS = 10.0 * kDeg;

// Six positions — z down and up, then the platform tilted ±90° about its
// y axis at two headings — and three full turns of the outer axis, each
// between moves. The unit sits at 45° yaw on the platform so that its x and
// y accelerometers both see gravity when the platform tilts.
sim::TableProfile SixPositionsAndThreeTurns() {
  using K = sim::TableSegment::Kind;
  sim::TableProfile p;
  p.name = "six-positions-three-turns";
  p.mount_rpy_rad = {0.0, 0.0, 45.0 * kDeg};
  p.angular_acceleration_rad_s2 = 10.0 * kDeg;
  p.thermal.ambient_degc = 25.0;
  const auto move = [&](double outer_deg, double inner_deg) {
    p.segments.push_back({K::kMoveTo, 0, kTableRateRadS, outer_deg * kDeg, inner_deg * kDeg});
  };
  const auto hold = [&](double s) { p.segments.push_back({K::kHold, s, 0, 0, 0}); };
  hold(kHoldS);
  for (auto [outer, inner] : {std::pair{0.0, 180.0}, {0.0, 90.0}, {0.0, 270.0}, {90.0, 90.0}, {90.0, 270.0}}) {
    move(outer, inner);
    hold(kHoldS);
  }
  for (double inner : {0.0, 90.0, 180.0}) {
    move(0.0, inner);
    hold(30.0);
    p.segments.push_back({K::kRotateOuter, 36.0 + 1.0, kTableRateRadS, 0, 0});
    hold(30.0);
  }
  return p;
}

bool SameAttitude(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Matrix3d d = nav::EulerToDcm(a).transpose() * nav::EulerToDcm(b);
  return std::acos(std::clamp((d.trace() - 1.0) / 2.0, -1.0, 1.0)) < 1e-9;
}

// The recorded files joined: the samples of every move (a motion that ends
// in another attitude than it started from) are dropped, each file after a
// move is a segment, and the files follow one another in time.
BenchRun RecordedFilesJoined(const BenchRun& run) {
  BenchRun joined;
  joined.metadata = run.metadata;
  joined.has_temperature = run.has_temperature;
  const auto& s = run.samples;
  const double dt = run.NominalIntervalS();
  size_t k = 0;
  bool after_move = false;
  while (k < s.size()) {
    if (k > 0 && !SameAttitude(s[k].ref_rpy_rad, s[k - 1].ref_rpy_rad)) {
      // A motion from sample k−1's attitude: find where it stops.
      size_t end = k;
      while (end + 1 < s.size() && !SameAttitude(s[end + 1].ref_rpy_rad, s[end].ref_rpy_rad)) ++end;
      if (!SameAttitude(s[end].ref_rpy_rad, s[k - 1].ref_rpy_rad)) {
        k = end + 1;  // a move: not recorded
        after_move = true;
        continue;
      }
    }
    if (after_move) joined.metadata.segment_starts.push_back(joined.samples.size());
    after_move = false;
    ImuSample sample = s[k];
    sample.t_s = static_cast<double>(joined.samples.size() + 1) * dt;
    joined.samples.push_back(sample);
    ++k;
  }
  return joined;
}

struct Truth {
  std::string name;
  double value;
};

sim::SimulatedUnit UnitWithCalibrationErrors(uint64_t seed, std::vector<Truth>& truth) {
  sim::SimulatedUnit unit = NavigationGradeUnit();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> scale(-300e-6, 300e-6), acc_bias(-1e-3, 1e-3),
      gyro_bias(-0.05 * kDegPerHour, 0.05 * kDegPerHour);
  const char* axes[] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i) {
    for (auto [family, draw] : {std::pair<std::string, double>{"acc_scale_factor", scale(rng)},
                                {"acc_turn_on_bias", acc_bias(rng)},
                                {"gyro_turn_on_bias", gyro_bias(rng)}}) {
      const std::string name = family + "." + axes[i];
      auto effect = sim::ParseTrueEffect(absl::StrFormat("%s=%.17g", name, draw));
      EXPECT_TRUE(effect.ok()) << effect.status();
      unit.effects.insert(unit.effects.end(), effect->begin(), effect->end());
      truth.push_back({name, draw});
    }
  }
  return unit;
}

const ParameterEstimate* Find(const AnalysisReport& r, const std::string& name) {
  for (const ParameterEstimate& p : r.identified) {
    if (p.name == name) return &p;
  }
  return nullptr;
}

AnalysisRequest WithCalibrationEffects() {
  AnalysisRequest request;
  request.nominal = TrueBaseModel(NavigationGradeUnit());
  request.baseline_effects = {"acc_scale_factor", "acc_turn_on_bias", "gyro_turn_on_bias"};
  return request;
}

TEST(MultiPosition, TheJoinedFilesRecoverTheCalibrationAndOneFileAloneCannot) {
  for (uint64_t seed : {31u, 32u}) {
    std::vector<Truth> truth;
    const sim::SimulatedUnit unit = UnitWithCalibrationErrors(seed, truth);
    const sim::SimulatedRun simulated = SimulateOrDie(unit, SixPositionsAndThreeTurns(), kRateHz, seed);
    const BenchRun joined = RecordedFilesJoined(simulated.run);
    ASSERT_EQ(joined.metadata.segment_starts.size(), 8u) << "six positions and three turns are nine files";
    AnalysisOptions options;
    options.identify = false;
    options.remove_dominant_constants = false;  // every constant estimated by the joint filter
    auto analysis = Analyze(joined, WithCalibrationEffects(), options);
    ASSERT_TRUE(analysis.ok()) << analysis.status();
    for (const Truth& t : truth) {
      const ParameterEstimate* p = Find(analysis->report, t.name);
      ASSERT_NE(p, nullptr) << t.name;
      EXPECT_LT(std::abs(p->value - t.value), 3.0 * p->std_error)
          << "seed " << seed << " " << t.name << ": " << p->value << " ± " << p->std_error << ", true " << t.value;
      EXPECT_TRUE(ObservableByRun(*p)) << t.name << ": SE " << p->std_error << ", prior " << p->prior_std;
    }

    // The first file alone: level, still, one attitude.
    BenchRun first = joined;
    first.samples.resize(joined.metadata.segment_starts.front());
    first.metadata.segment_starts.clear();
    auto alone = Analyze(first, WithCalibrationEffects(), options);
    ASSERT_TRUE(alone.ok()) << alone.status();
    for (const char* name : {"acc_scale_factor.x", "acc_scale_factor.y", "acc_scale_factor.z", "acc_turn_on_bias.z"}) {
      const ParameterEstimate* p = Find(alone->report, name);
      ASSERT_NE(p, nullptr) << name;
      EXPECT_FALSE(ObservableByRun(*p)) << name << ": SE " << p->std_error << ", prior " << p->prior_std
                                        << ", correlation " << p->max_correlation << " with " << p->correlated_with;
    }
    bool noted = false;
    for (const std::string& note : alone->report.notes) noted |= note.find("not observable from this run") == 0;
    EXPECT_TRUE(noted);
  }
}

}  // namespace
}  // namespace insdiag::engine::testing
