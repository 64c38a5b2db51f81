// A multi-position test: six static positions and three turns recorded as
// separate bench-run files with unrecorded moves between them, joined as
// `insdiag join` joins them (benchrun::JoinBenchRunFiles) into one file of
// segments, read back and analysed. The joint analysis aligns each segment
// anew and shares the sensor errors, so that it recovers what no single
// position tells: the accelerometer scale factors and biases and the gyro
// biases, within 3 standard errors. One file alone leaves unobservable what
// its geometry cannot tell, and the report says exactly which and why
// (docs/MULTI_POSITION.md, "What one position or one turn tells").
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>

#include <absl/strings/str_format.h>

#include "insdiag/api/report_codec.h"
#include "insdiag/benchrun/bench_run_csv.h"
#include "insdiag/benchrun/bench_run_join.h"
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

// By the matrices' difference, about √2 times the angle between them: the
// angle from acos of the trace resolves no better than 2e-8 rad.
bool SameAttitude(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return (nav::EulerToDcm(a) - nav::EulerToDcm(b)).norm() < 1e-9;
}

// What the bench records of the simulated session: one file per position or
// turn, from the end of one move (a motion that ends in another attitude than
// it started from) to the start of the next, each on the session's clock.
std::vector<BenchRun> RecordedFiles(const BenchRun& session) {
  std::vector<BenchRun> files(1);
  const auto& s = session.samples;
  size_t k = 0;
  while (k < s.size()) {
    // A still sample, or the first of a motion from sample k−1's attitude.
    size_t end = k;
    if (k > 0 && !SameAttitude(s[k].ref_rpy_rad, s[k - 1].ref_rpy_rad)) {
      while (end + 1 < s.size() && !SameAttitude(s[end + 1].ref_rpy_rad, s[end].ref_rpy_rad)) ++end;
      if (!SameAttitude(s[end].ref_rpy_rad, s[k - 1].ref_rpy_rad)) {
        k = end + 1;  // a move: not recorded
        if (!files.back().samples.empty()) files.emplace_back();
        continue;
      }
    }
    // Still, or a turn back to where it started: recorded.
    files.back().samples.insert(files.back().samples.end(), s.begin() + static_cast<std::ptrdiff_t>(k),
                                s.begin() + static_cast<std::ptrdiff_t>(end + 1));
    k = end + 1;
  }
  for (BenchRun& f : files) {
    f.metadata = session.metadata;
    f.has_temperature = session.has_temperature;
  }
  return files;
}

// A fresh directory for this process's files.
std::filesystem::path FilesDirectory(const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / absl::StrFormat("insdiag-%s-%d", name, static_cast<int>(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
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

// The simulated session as the bench records it: nine files under `dir`.
struct RecordedTest {
  std::vector<Truth> truth;
  std::vector<std::filesystem::path> files;
};
RecordedTest RecordSession(uint64_t seed, const std::filesystem::path& dir) {
  RecordedTest test;
  const sim::SimulatedUnit unit = UnitWithCalibrationErrors(seed, test.truth);
  const sim::SimulatedRun simulated = SimulateOrDie(unit, SixPositionsAndThreeTurns(), kRateHz, seed);
  std::vector<BenchRun> recorded = RecordedFiles(simulated.run);
  // The table's encoders are logged with the samples (filter/observation.h).
  for (BenchRun& file : recorded) file.metadata.DeclareAttitudeReadout(true);
  EXPECT_EQ(recorded.size(), 9u) << "six positions and three turns are nine files";
  for (size_t i = 0; i < recorded.size(); ++i) {
    test.files.push_back(dir / absl::StrFormat("file-%d.csv", i + 1));
    EXPECT_TRUE(benchrun::WriteBenchRunFile(recorded[i], test.files.back()).ok());
  }
  return test;
}

AnalysisOptions EveryConstantInTheFilter() {
  AnalysisOptions options;
  options.identify = false;
  options.remove_dominant_constants = false;  // every constant estimated by the joint filter
  return options;
}

std::string Described(const ParameterEstimate& p) {
  const api::Observability o = api::ObservabilityOf(p);
  return absl::StrFormat("%s = %.3g ± %.3g (prior %.3g, correlation %+.3f with %s): %s %s", p.name, p.value,
                         p.std_error, p.prior_std, p.max_correlation, p.correlated_with,
                         v1::IdentifiedParameter::Observability_Name(o.verdict), o.note);
}

TEST(MultiPosition, TheJoinedFilesRecoverTheCalibrationWithin3StandardErrors) {
  for (uint64_t seed : {31u, 32u}) {
    const std::filesystem::path dir = FilesDirectory(absl::StrFormat("multi-position-joined-%d", seed));
    const RecordedTest recorded = RecordSession(seed, dir);
    ASSERT_EQ(recorded.files.size(), 9u);
    // As `insdiag join file-1.csv … file-9.csv -o test.csv`, then `insdiag analyze test.csv`.
    auto joined = benchrun::JoinBenchRunFiles(recorded.files);
    ASSERT_TRUE(joined.ok()) << joined.status();
    ASSERT_TRUE(benchrun::WriteBenchRunFile(*joined, dir / "test.csv").ok());
    auto test = benchrun::ReadBenchRunFile(dir / "test.csv");
    ASSERT_TRUE(test.ok()) << test.status();
    EXPECT_EQ(test->metadata.format, benchrun::kFormatV2);
    ASSERT_EQ(test->metadata.segment_starts.size(), 8u);
    auto analysis = Analyze(*test, WithCalibrationEffects(), EveryConstantInTheFilter());
    ASSERT_TRUE(analysis.ok()) << analysis.status();
    for (const Truth& t : recorded.truth) {
      const ParameterEstimate* p = Find(analysis->report, t.name);
      ASSERT_NE(p, nullptr) << t.name;
      std::printf("seed %d %s, true %.3g\n", static_cast<int>(seed), Described(*p).c_str(), t.value);
      EXPECT_LT(std::abs(p->value - t.value), 3.0 * p->std_error)
          << "seed " << seed << " " << t.name << ": " << p->value << " ± " << p->std_error << ", true " << t.value;
      EXPECT_EQ(api::ObservabilityOf(*p).verdict, v1::IdentifiedParameter::OBSERVABLE) << Described(*p);
    }
    for (const std::string& note : analysis->report.notes) {
      EXPECT_EQ(note.find("not observable from this run"), std::string::npos) << note;
    }
    std::filesystem::remove_all(dir);
  }
}

// What one file tells, from its geometry (docs/MULTI_POSITION.md): a position
// shows each accelerometer one force f, so only s·f + b is known — s and b
// apart where f ≠ 0 (inseparable), b alone where f = 0 (s never excited).
// The table's encoders are read while it stands still (filter/observation.h):
// a gyro's bias turns the unit away from the encoders' attitude at b·t about
// its own axis, so every gyro's bias is told by any file with a still
// stretch, the heading gyro's too (without the attitude it reaches the
// velocities only through the Earth's rate, ∝ gΩ cos L·b·t³/6, and on a
// tilted position the x and y gyros, which share the vertical, were
// inseparable). A turn about the vertical leaves the forces on the body's
// axes as they were.
using Verdict = v1::IdentifiedParameter::Observability;
constexpr Verdict kObservable = v1::IdentifiedParameter::OBSERVABLE;
constexpr Verdict kNotExcited = v1::IdentifiedParameter::NOT_EXCITED;
constexpr Verdict kInseparable = v1::IdentifiedParameter::INSEPARABLE;
constexpr Verdict kWeak = v1::IdentifiedParameter::WEAKLY_DETERMINED;

struct OneFile {
  int file;  // 1-based, in recording order
  const char* what;
  // acc_scale_factor, acc_turn_on_bias, gyro_turn_on_bias, each x, y, z
  std::array<std::array<Verdict, 3>, 3> verdicts;
};
constexpr OneFile kOneFileAlone[] = {
    {1, "level, z down, still 300 s",
     {{{kNotExcited, kNotExcited, kInseparable}, {kObservable, kObservable, kInseparable},
       {kObservable, kObservable, kObservable}}}},
    {3, "tilted: x and y at 45° to gravity, z level; still 300 s",
     {{{kInseparable, kInseparable, kNotExcited}, {kInseparable, kInseparable, kObservable},
       {kObservable, kObservable, kObservable}}}},
    {7, "level, one turn about the vertical, 97 s",
     {{{kNotExcited, kNotExcited, kInseparable}, {kObservable, kObservable, kInseparable},
       {kObservable, kObservable, kObservable}}}},
    {8, "tilted, one turn about the vertical, 97 s",
     {{{kInseparable, kInseparable, kNotExcited}, {kInseparable, kInseparable, kObservable},
       {kObservable, kObservable, kObservable}}}},
};

TEST(MultiPosition, OneFileAloneLeavesUnobservableWhatItsGeometryCannotTell) {
  constexpr const char* kFamilies[] = {"acc_scale_factor", "acc_turn_on_bias", "gyro_turn_on_bias"};
  constexpr const char* kAxes[] = {"x", "y", "z"};
  for (uint64_t seed : {31u, 32u}) {
    const std::filesystem::path dir = FilesDirectory(absl::StrFormat("multi-position-alone-%d", seed));
    const RecordedTest recorded = RecordSession(seed, dir);
    ASSERT_EQ(recorded.files.size(), 9u);
    for (const OneFile& one : kOneFileAlone) {
      auto run = benchrun::ReadBenchRunFile(recorded.files[static_cast<size_t>(one.file - 1)]);
      ASSERT_TRUE(run.ok()) << run.status();
      auto alone = Analyze(*run, WithCalibrationEffects(), EveryConstantInTheFilter());
      ASSERT_TRUE(alone.ok()) << alone.status();
      std::string note;
      for (const std::string& n : alone->report.notes) {
        if (n.starts_with("not observable from this run")) note = n;
      }
      std::printf("seed %d, file %d (%s):\n", static_cast<int>(seed), one.file, one.what);
      for (size_t f = 0; f < 3; ++f) {
        for (size_t a = 0; a < 3; ++a) {
          const std::string name = absl::StrFormat("%s.%s", kFamilies[f], kAxes[a]);
          const ParameterEstimate* p = Find(alone->report, name);
          ASSERT_NE(p, nullptr) << name;
          std::printf("  %s\n", Described(*p).c_str());
          const Verdict expected = one.verdicts[f][a];
          EXPECT_EQ(api::ObservabilityOf(*p).verdict, expected)
              << "file " << one.file << " (" << one.what << "), expected "
              << v1::IdentifiedParameter::Observability_Name(expected) << ": " << Described(*p);
          // The report's note lists exactly the parameters it cannot tell.
          EXPECT_EQ(note.find(name) != std::string::npos, expected != kObservable)
              << "file " << one.file << ": " << name << " in the note \"" << note << "\"";
        }
      }
    }
    std::filesystem::remove_all(dir);
  }
}

}  // namespace
}  // namespace insdiag::engine::testing
