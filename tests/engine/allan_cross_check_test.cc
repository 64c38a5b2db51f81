// The Allan analysis (engine/include/insdiag/engine/ident/allan.h) against an
// independent computation: numpy and scipy in tests/engine/allan_check.py, on
// simulated segments and on the real ring-laser-gyro record.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <system_error>
#include <vector>

#include "allan_scenarios.h"
#include "insdiag/benchrun/bench_run_csv.h"
#include "insdiag/engine/ident/allan.h"
#include "insdiag/engine/model/parameter_key.h"
#include "scenarios.h"
#include "support/subprocess.h"

namespace insdiag::engine::ident {
namespace {

using namespace allan_scenarios;
using testing::kDegPerHour;

std::string MList(const std::vector<AllanPoint>& curve) {
  std::string s;
  for (const AllanPoint& p : curve) {
    if (!s.empty()) s += ',';
    s += std::to_string(p.m);
  }
  return s;
}

// Terms of a fit in allan_check.py's letters ("Q,N,M").
std::string TermLetters(const AllanFit& fit) {
  static constexpr const char* kLetter[kAllanParameterCount] = {"Q", "N", "B", "K", "R", "M", nullptr};
  std::string s;
  for (int k = 0; k < kAllanParameterCount; ++k) {
    if (kLetter[k] == nullptr || !fit.parameters[static_cast<size_t>(k)].included) continue;
    if (!s.empty()) s += ',';
    s += kLetter[k];
  }
  return s;
}

std::string FitRequest(const std::string& channel, const AllanFit& fit) {
  char delta[32];
  std::snprintf(delta, sizeof(delta), "%.17g", fit.discrepancy);
  return channel + ":" + TermLetters(fit) + ":" + delta;
}

struct CheckOutput {
  std::map<std::pair<std::string, int64_t>, std::pair<double, double>> adev;  // (channel, m) → (σ̂, ν)
  std::map<std::pair<std::string, std::string>, double> fit;                 // (channel, parameter) → value
};

CheckOutput RunCheck(std::vector<std::string> args) {
  args.insert(args.begin(), {"/usr/bin/python3", std::string(INSDIAG_SOURCE_DIR) + "/tests/engine/allan_check.py"});
  const std::filesystem::path work = insdiag::testing::MakeTempDir("allan-check");
  auto done = insdiag::testing::RunToCompletion(args, work, std::chrono::seconds(120));
  std::error_code ignored;
  std::filesystem::remove_all(work, ignored);  // the check writes nothing a failure would need
  CheckOutput out;
  EXPECT_TRUE(done.ok()) << done.status();
  if (!done.ok()) return out;
  EXPECT_EQ(done->exit_status, 0) << done->stderr_text;
  std::istringstream in(done->stdout_text);
  std::string kind, channel;
  while (in >> kind >> channel) {
    if (kind == "adev") {
      int64_t m = 0;
      double v = 0, edf = 0;
      in >> m >> v >> edf;
      out.adev[{channel, m}] = {v, edf};
    } else if (kind == "fit") {
      std::string name;
      double v = 0;
      in >> name >> v;
      out.fit[{channel, name}] = v;
    } else {
      std::string rest;
      std::getline(in, rest);
    }
  }
  return out;
}

// Writes the analysed samples: int64 rows, int64 cols (7), then per sample
// the segment index and the six rates, little-endian doubles.
void WriteSamples(const std::string& path, const BenchRun& run, const std::vector<StaticSegment>& segments) {
  std::vector<double> data;
  for (size_t s = 0; s < segments.size(); ++s) {
    for (size_t k = segments[s].first_sample; k < segments[s].end_sample; ++k) {
      const ImuSample& x = run.samples[k];
      data.insert(data.end(), {static_cast<double>(s), x.gyro_rad_s.x(), x.gyro_rad_s.y(), x.gyro_rad_s.z(),
                               x.acc_mps2.x(), x.acc_mps2.y(), x.acc_mps2.z()});
    }
  }
  const int64_t header[2] = {static_cast<int64_t>(data.size() / 7), 7};
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(header), sizeof(header));
  f.write(reinterpret_cast<const char*>(data.data()), static_cast<std::streamsize>(data.size() * sizeof(double)));
  ASSERT_TRUE(f.good());
}

// The parameters of a fit compared with allan_check.py's, keyed as it prints them.
std::vector<std::pair<std::string, AllanParameter>> ComparedParameters(const AllanFit& fit) {
  std::vector<std::pair<std::string, AllanParameter>> out;
  for (int k = 0; k < kAllanParameterCount; ++k) {
    const auto p = static_cast<AllanParameter>(k);
    if (fit[p].included) out.emplace_back(AllanParameterName(p), p);
  }
  return out;
}

// Compares every point of the engine's curves with allan_check.py's: the
// deviations to 1e-9, and ν (`check_edf`) or the intervals (otherwise).
// Returns the largest relative difference of the deviations.
double CompareCurves(const AllanResult& r, const CheckOutput& py, bool check_edf) {
  double worst = 0.0;
  for (const AllanChannel& ch : r.channels) {
    for (const AllanPoint& p : ch.curve) {
      auto it = py.adev.find({ch.name, p.m});
      if (it == py.adev.end()) {
        ADD_FAILURE() << ch.name << " m = " << p.m << " missing";
        continue;
      }
      worst = std::max(worst, std::abs(it->second.first / p.adev - 1.0));
      EXPECT_NEAR(it->second.first / p.adev, 1.0, 1e-9) << ch.name << " m = " << p.m;
      if (check_edf) {
        EXPECT_NEAR(it->second.second / p.edf, 1.0, 1e-9) << ch.name << " m = " << p.m;
      } else {
        EXPECT_GT(it->second.first, p.ci_low) << ch.name << " m = " << p.m;
        EXPECT_LT(it->second.first, p.ci_high) << ch.name << " m = " << p.m;
      }
    }
  }
  std::printf("largest relative ADEV difference: %.2e\n", worst);
  return worst;
}


// The samples of the static segments of a run with holds of 900, 90 and 300 s
// go to numpy, which pools the overlapping Allan variance over the segments
// itself (cumulative sums in extended precision) at the same cluster sizes:
// the deviations agree to 1e-9. Its ν (the same published formulas, coded
// again) agree too. Then scipy fits the terms the engine selected, with the
// same weighting rule and discrepancy: the parameters agree within 2% — the
// optimisers (Ceres LM, scipy TRF) and their starts differ, nothing else; in
// practice they agree to ~1e-5 — and within the engine's standard errors.
TEST(AllanCrossCheckTest, SimulatedSegmentsAgainstNumpy) {
  const sim::SimulatedRun s = testing::SimulateOrDie(HiddenTermsUnit(HiddenTerms{}), HoldsProfile(), 100.0, 9);
  auto r = AllanAnalysis(s.run, AllanOptions{});
  ASSERT_TRUE(r.ok()) << r.status();
  ASSERT_EQ(r->segments.size(), 3u);
  const std::string path = (insdiag::testing::MakeTempDir("allan-samples") / "samples.f64").string();
  WriteSamples(path, s.run, r->segments);
  char tau0[32];
  std::snprintf(tau0, sizeof(tau0), "%.17g", r->tau0_s);
  std::vector<std::string> args = {"--samples", path, "--tau0", tau0, "--m", MList(r->channels[0].curve)};
  for (const AllanChannel& ch : r->channels) args.insert(args.end(), {"--fit", FitRequest(ch.name, ch.fit)});
  const CheckOutput py = RunCheck(args);
  CompareCurves(*r, py, /*check_edf=*/true);
  for (const AllanChannel& ch : r->channels) {
    for (const auto& [name, p] : ComparedParameters(ch.fit)) {
      auto it = py.fit.find({ch.name, name});
      ASSERT_NE(it, py.fit.end()) << ch.name << " " << name;
      const AllanTermEstimate& t = ch.fit[p];
      std::printf("%s %-12s engine %.8g scipy %.8g (%+.2e)\n", ch.name.c_str(), name.c_str(), t.value, it->second,
                  it->second / t.value - 1.0);
      EXPECT_NEAR(it->second / t.value, 1.0, 0.02) << ch.name << " " << name;
      EXPECT_LT(std::abs(it->second - t.value), t.std_error) << ch.name << " " << name;
    }
  }
}

// The README's table: overlapping ADEV of the gyro channels in °/h at
// τ = 0.01 … 300 s, three significant figures.
struct ReadmeRow {
  double tau_s;
  double value_deg_h[3];  // x, y, z
  double last_digit[3];   // the unit of the last printed digit
};
constexpr ReadmeRow kReadme[] = {
    {0.01, {56.8, 53.1, 34.2}, {0.1, 0.1, 0.1}},   {0.1, {104.6, 55.6, 55.4}, {0.1, 0.1, 0.1}},
    {1.0, {60.7, 17.4, 8.71}, {0.1, 0.1, 0.01}},   {10.0, {14.7, 8.42, 1.49}, {0.1, 0.01, 0.01}},
    {30.0, {7.21, 4.35, 0.67}, {0.01, 0.01, 0.01}}, {100.0, {2.66, 2.07, 0.25}, {0.01, 0.01, 0.01}},
    {300.0, {0.89, 0.87, 0.078}, {0.01, 0.01, 0.001}},
};

// The real ring-laser-gyro record (data/real, imported from its PSINS log by
// the build: tests/CMakeLists.txt): the analysis completes on its one
// segment; numpy reproduces every deviation to 1e-9 (inside the engine's
// intervals by far); scipy's fit of the independent curve agrees with the
// engine's fitted terms within their standard errors — the selected terms
// and, on the gyros, a fit of Q and N alone (the selection resolves neither:
// the record is dominated by the dither and by the vehicle's sway, see
// docs/IDENTIFICATION.md).
//
// README: its table matches the overlapping ADEV of these same samples at
// m = τ/0.01 s in °/h. 20 of its 21 entries agree with the engine's to the
// printed digits (e.g. x: 56.81, 104.57, 60.66, 14.69, 7.213, 2.661, 0.892);
// gyro z at 300 s reads 0.078 where the engine (and numpy) give 0.07746, 0.7%
// lower — a rounding or a slightly different sample span on their side, far
// inside the interval (ν ≈ 3.5 there). Asserted: within 1% and inside the CIs.
TEST(AllanCrossCheckTest, RealRingLaserGyroRecord) {
  const std::string path = INSDIAG_REAL_RECORD_CSV;
  auto run = benchrun::ReadBenchRunFile(path);
  ASSERT_TRUE(run.ok()) << run.status();
  // The estimator against numpy's on the same samples, so without the jump
  // test, which numpy's estimator does not have.
  AllanOptions estimator;
  estimator.jump_alpha = 0.0;
  auto r = AllanAnalysis(*run, estimator);
  ASSERT_TRUE(r.ok()) << r.status();
  ASSERT_EQ(r->segments.size(), 1u);
  EXPECT_EQ(r->samples_used, run->samples.size());
  const std::vector<size_t> segment = {run->samples.size()};

  // With it, as the analysis runs: the gyros' curves are the estimator's
  // (their start-up transients and knocks do not persist over a segment's
  // length); an accelerometer whose 60-second mean moves may be cut.
  auto with_jumps = AllanAnalysis(*run, AllanOptions{});
  ASSERT_TRUE(with_jumps.ok()) << with_jumps.status();
  for (const AllanChannel& ch : with_jumps->channels) {
    for (const RateJump& j : ch.jumps) {
      std::printf("%s cut at %.2f s: %.3g %s, z %.1f, window %lld\n", ch.name.c_str(), j.time_s,
                  j.size, ch.unit.c_str(), j.z, static_cast<long long>(j.window));
    }
    if (ch.sensor == Sensor::kGyro) {
      EXPECT_TRUE(ch.jumps.empty()) << ch.name;
    }
  }

  AllanOptions qn;
  qn.candidates = {.quantization = true, .white = true, .bias_instability = false,
                   .rate_random_walk = false, .rate_ramp = false, .markov = false};
  qn.select_terms = false;
  std::vector<AllanFit> forced;
  std::vector<std::string> args = {"--csv", path, "--m", MList(r->channels[0].curve)};
  for (const AllanChannel& ch : r->channels) {
    std::printf("%s\n", Describe(ch).c_str());
    EXPECT_FALSE(ch.curve.empty());
    args.insert(args.end(), {"--fit", FitRequest(ch.name, ch.fit)});
    if (ch.sensor == Sensor::kGyro) {
      std::vector<AllanPoint> curve = ch.curve;
      auto fit = FitAllanCurve(curve, r->tau0_s, segment, qn);
      ASSERT_TRUE(fit.ok()) << fit.status();
      forced.push_back(*fit);
      args.insert(args.end(), {"--fit", FitRequest(ch.name + "@qn", *fit)});
    }
  }
  const CheckOutput py = RunCheck(args);
  CompareCurves(*r, py, /*check_edf=*/false);

  for (const AllanChannel& ch : r->channels) {
    auto compare = [&](const AllanFit& fit, const std::string& label) {
      for (const auto& [name, p] : ComparedParameters(fit)) {
        auto it = py.fit.find({label, name});
        ASSERT_NE(it, py.fit.end()) << label << " " << name;
        const AllanTermEstimate& t = fit[p];
        std::printf("%-10s %-12s engine %.6g ± %.2g, scipy %.6g (%+.1e)\n", label.c_str(), name.c_str(), t.value,
                    t.std_error, it->second, it->second / t.value - 1.0);
        if (std::isfinite(t.std_error)) {
          EXPECT_LT(std::abs(it->second - t.value), t.std_error) << label << " " << name;
          continue;
        }
        // Driven to its lower bound on both sides (not resolvable): neither
        // value adds a thousandth to σ̂² anywhere on the curve.
        ASSERT_NE(p, AllanParameter::kMarkovTau);
        for (double v : {t.value, it->second}) {
          AllanNoiseTerms alone;
          (p == AllanParameter::kQuantization ? alone.quantization
           : p == AllanParameter::kWhiteDensity ? alone.white_density
           : p == AllanParameter::kBiasInstability ? alone.bias_instability
           : p == AllanParameter::kRateRandomWalk ? alone.rate_random_walk
                                                   : alone.rate_ramp) = v;
          for (const AllanPoint& point : ch.curve) {
            EXPECT_LT(ModelAllanVariance(alone, point.tau_s), 1e-3 * point.adev * point.adev) << label << " " << name;
          }
        }
      }
    };
    compare(ch.fit, ch.name);
    if (ch.sensor == Sensor::kGyro) {
      const AllanFit& f = forced[static_cast<size_t>(ch.axis)];
      EXPECT_TRUE(f[AllanParameter::kQuantization].included && f[AllanParameter::kWhiteDensity].included);
      EXPECT_FALSE(f.adequate);  // dither and sway: the note says so
      EXPECT_FALSE(f.notes.empty());
      compare(f, ch.name + "@qn");
    }
  }

  // The README table.
  std::vector<int64_t> m;
  std::string m_list;
  for (const ReadmeRow& row : kReadme) {
    m.push_back(std::llround(row.tau_s / r->tau0_s));
    m_list += (m_list.empty() ? "" : ",") + std::to_string(m.back());
  }
  const CheckOutput readme_py = RunCheck({"--csv", path, "--m", m_list});
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<std::vector<double>> rates(1);
    for (const ImuSample& sample : run->samples) rates[0].push_back(sample.gyro_rad_s[axis]);
    const std::vector<AllanPoint> curve = OverlappingAllanCurve(rates, r->tau0_s, m, AllanOptions{});
    ASSERT_EQ(curve.size(), m.size());
    for (size_t i = 0; i < m.size(); ++i) {
      const double engine = curve[i].adev / kDegPerHour;
      const double readme = kReadme[i].value_deg_h[axis];
      const double numpy = readme_py.adev.at({std::string(kSensorChannelNames[axis]), m[i]}).first / kDegPerHour;
      std::printf("gyro_%s τ %6.2f s: engine %.5g °/h [%.4g, %.4g], numpy %.5g, README %.3g\n",
                  std::string(AxisName(axis)).c_str(), kReadme[i].tau_s, engine,
                  curve[i].ci_low / kDegPerHour, curve[i].ci_high / kDegPerHour, numpy, readme);
      EXPECT_NEAR(numpy / engine, 1.0, 1e-9);
      EXPECT_NEAR(engine / readme, 1.0, 0.01) << "axis " << axis;
      if (std::abs(engine - readme) > 0.5 * kReadme[i].last_digit[axis]) {
        std::printf("  differs beyond the README's rounding (%.2f%%)\n", 100.0 * (engine / readme - 1.0));
      }
      EXPECT_GT(readme * kDegPerHour, curve[i].ci_low);
      EXPECT_LT(readme * kDegPerHour, curve[i].ci_high);
    }
  }
}

}  // namespace
}  // namespace insdiag::engine::ident
