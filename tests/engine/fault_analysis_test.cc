// Faulty units through the whole analysis: a bias step at an unknown onset
// is named with its onset and the verdict, and a healthy unit is not called
// faulty, over seeds, axes and onsets (the scenario matrix in
// docs/FAULT_SCENARIOS.md runs more of both, on both simulators). The Monte
// Carlo tests run a few of their runs in the suite and all of them in the
// sweep (tests/support/monte_carlo.h, scripts/sweeps.sh).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "insdiag/engine/analysis.h"
#include "scenarios.h"
#include "support/monte_carlo.h"

namespace insdiag::engine {
namespace {

// The analysis of one hour of static tilts at 10 Hz with its datasheet.
AnalysisReport AnalyseOrDie(const sim::SimulatedUnit& unit, uint64_t seed) {
  const auto sim = testing::SimulateOrDie(unit, testing::BuiltinProfileOrDie("positions"), 10.0, seed);
  auto analysis = Analyze(sim.run, {}, AnalysisOptions{});
  EXPECT_TRUE(analysis.ok()) << analysis.status();
  return analysis.ok() ? analysis->report : AnalysisReport{};
}

const EffectCandidate* TopCandidate(const AnalysisReport& r) {
  return r.effect_candidates.empty() ? nullptr : &r.effect_candidates.front();
}

// The claim: a bias step of five drift σ on any sensor axis is named first
// (Holm p < 0.01) in 95 % of runs, its onset within 60 s in 95 % of those,
// and the unit is FAULTY in 95 %; each count's threshold fails falsely with
// probability ≤ 5 % at those rates (what the six-run test's 5, 4 and 5 of 6
// allowed). The sweep runs the six axes (gyro and accelerometer x, y, z);
// the suite three of them, gyro x, gyro z and accelerometer y, each with
// the seed and onset it has in the sweep: at least 2 of 3 named and FAULTY,
// which catches a rate of 50 % with probability 0.50 and one of 30 % with
// 0.78 (six runs: 0.89 and 0.99).
TEST(FaultyUnit, BiasStepsOfFiveDriftSigmaAreNamedWithTheirOnsetAndMakeTheUnitFaulty) {
  constexpr double kClaimedRate = 0.95, kFalseFailure = 0.05;
  constexpr int kAxes = 6;
  const int sample = insdiag::testing::Runs({.suite = 3, .sweep = kAxes});
  std::mt19937_64 rng(77);
  std::uniform_real_distribution<double> onset(1200.0, 3000.0);
  int index = 0, runs = 0, named_first = 0, onset_within_60_s = 0, faulty = 0;
  for (Sensor sensor : {Sensor::kGyro, Sensor::kAccelerometer}) {
    for (int axis = 0; axis < 3; ++axis) {
      auto unit = testing::NavigationGradeUnit();
      const double sigma = (sensor == Sensor::kGyro ? unit.gyro : unit.acc).bias[static_cast<size_t>(axis)].sigma;
      const double t0 = onset(rng);
      const uint64_t seed = 300 + static_cast<uint64_t>(index);
      // `sample` of the six, spread over them (all six in the sweep).
      const bool in_sample = (index * sample) % kAxes < sample;
      ++index;
      if (!in_sample) continue;
      unit.bias_steps.push_back({sensor, axis, t0, (axis % 2 == 0 ? 5.0 : -5.0) * sigma});
      const AnalysisReport r = AnalyseOrDie(unit, seed);
      ++runs;
      const std::string expected = std::string(sensor == Sensor::kGyro ? "gyro" : "acc") + "_bias_step." + "xyz"[axis];
      const EffectCandidate* top = TopCandidate(r);
      ASSERT_NE(top, nullptr);
      std::printf("%s at %.0f s: top %s (Holm p %.2g) onset %.0f ± %.0f s, verdict %s\n", expected.c_str(), t0,
                  top->name.c_str(), top->p_value_holm, top->onset_s.value_or(-1.0), top->onset_std_s,
                  VerdictName(r.verdict));
      faulty += r.verdict == Verdict::kFaulty ? 1 : 0;
      if (top->name != expected || !(top->p_value_holm < 0.01)) continue;
      ++named_first;
      onset_within_60_s += top->onset_s.has_value() && std::abs(*top->onset_s - t0) <= 60.0 ? 1 : 0;
    }
  }
  const int least = insdiag::testing::LeastSuccesses(runs, kClaimedRate, kFalseFailure);
  const int least_onsets = insdiag::testing::LeastSuccesses(named_first, kClaimedRate, kFalseFailure);
  std::printf("steps: named first %d of %d (at least %d), onset within 60 s %d (at least %d), FAULTY %d (at least %d)\n",
              named_first, runs, least, onset_within_60_s, least_onsets, faulty, least);
  ASSERT_GT(least, 0);
  EXPECT_GE(named_first, least);
  EXPECT_GE(onset_within_60_s, least_onsets);
  EXPECT_GE(faulty, least);
}

TEST(HealthyUnit, IsNotCalledFaultyAtTenHertz) {
  int good = 0, nothing_significant = 0;
  constexpr int kRuns = 4;
  for (int seed = 1; seed <= kRuns; ++seed) {
    const AnalysisReport r = AnalyseOrDie(testing::NavigationGradeUnit(), 700 + static_cast<uint64_t>(seed));
    good += r.verdict != Verdict::kFaulty ? 1 : 0;
    const bool any = std::any_of(r.effect_candidates.begin(), r.effect_candidates.end(), [](const EffectCandidate& c) {
      return c.identifiable && c.tested && c.p_value_holm < 0.01;
    });
    nothing_significant += any ? 0 : 1;
    if (any || r.verdict == Verdict::kFaulty) {
      std::printf("seed %d: verdict %s, top %s (Holm p %.2g)\n", seed, VerdictName(r.verdict),
                  r.effect_candidates.front().name.c_str(), r.effect_candidates.front().p_value_holm);
    }
  }
  // Each run is FAULTY with probability ≤ α = 1 %: all four pass with
  // probability ≥ 96 %, three or more with probability > 99.9 %.
  EXPECT_GE(good, kRuns - 1);
  EXPECT_GE(nothing_significant, kRuns - 1);
}

// A unit far from its type's nominal model, run without a datasheet: its
// gyro drifts ten times the nominal σ at a ninth of the nominal τ. The
// analysis starts from the nominal model (a prior, not the truth) and must
// find the drifts rather than call their misfit steps and walks. Over ten
// seeds (docs/IDENTIFICATION.md) σ came within 30 % on 28 of 30 axes and one
// run in ten was FAULTY. The claim: σ within 30 % on 90 % of the axes, and
// FAULTY in at most 10 % of the runs; each threshold fails falsely with
// probability ≤ 5 % at those rates (what the three-seed test's 7 of 9 and 2
// of 3 allowed). Each run costs minutes: the suite runs 2 seeds — σ within
// 30 % on at least 4 of 6 axes, which catches a rate of 50 % with
// probability 0.66, and at most 1 FAULTY, which catches a FAULTY rate of
// 50 % with 0.25, 70 % with 0.49 — and the sweep the ten of the docs
// (24 of 30 axes, at most 3 FAULTY: 0.98 against 60 %, 0.83 against 50 %).
TEST(FarFromNominal, GyroDriftsAreFoundWithoutFalseFaults) {
  const sim::SimulatedUnit nominal_unit = testing::NavigationGradeUnit();
  sim::SimulatedUnit unit = nominal_unit;
  for (auto& drift : unit.gyro.bias) drift = {10.0 * drift.sigma, 200.0};
  AnalysisRequest request;
  request.nominal = testing::TrueBaseModel(nominal_unit);
  constexpr double kClaimedWithin = 0.9, kClaimedFaulty = 0.1, kFalseFailure = 0.05;
  const int kRuns = insdiag::testing::Runs({.suite = 2, .sweep = 10});
  int not_faulty = 0, sigma_within_30_percent = 0;
  for (int seed = 1; seed <= kRuns; ++seed) {
    sim::SimulationOptions o;
    o.sample_rate_hz = 10.0;
    o.seed = 100 + static_cast<uint64_t>(seed);
    o.site = testing::TestSite();
    o.write_datasheet = false;
    const auto sim = sim::Simulate(unit, testing::BuiltinProfileOrDie("rotations"), o);
    ASSERT_TRUE(sim.ok()) << sim.status();
    auto analysis = Analyze(sim->run, request, AnalysisOptions{});
    ASSERT_TRUE(analysis.ok()) << analysis.status();
    const AnalysisReport& r = analysis->report;
    not_faulty += r.verdict != Verdict::kFaulty ? 1 : 0;
    for (int axis = 0; axis < 3; ++axis) {
      // Appended, not `std::string(…) + c + "…"`: at -O1 GCC 12 warns falsely
      // (-Warray-bounds) on the moved temporary.
      std::string name = "gyro_bias_gm.";
      name += "xyz"[axis];
      name += ".sigma";
      const auto p = std::find_if(r.identified.begin(), r.identified.end(),
                                  [&](const ParameterEstimate& e) { return e.name == name; });
      const double truth = unit.gyro.bias[static_cast<size_t>(axis)].sigma;
      const bool within = p != r.identified.end() && std::abs(p->value / truth - 1.0) <= 0.3;
      sigma_within_30_percent += within ? 1 : 0;
      std::printf("seed %d %s: %s\n", seed, name.c_str(),
                  p == r.identified.end() ? "not identified"
                                          : (std::to_string(p->value / truth) + " × truth").c_str());
    }
    std::printf("seed %d: verdict %s\n", seed, VerdictName(r.verdict));
  }
  const int most_faulty = insdiag::testing::MostAlarms(kRuns, kClaimedFaulty, kFalseFailure);
  const int least_within = insdiag::testing::LeastSuccesses(3 * kRuns, kClaimedWithin, kFalseFailure);
  std::printf("far from nominal: FAULTY %d of %d (at most %d), σ within 30 %% on %d of %d axes (at least %d)\n",
              kRuns - not_faulty, kRuns, most_faulty, sigma_within_30_percent, 3 * kRuns, least_within);
  ASSERT_LT(most_faulty, kRuns);
  EXPECT_LE(kRuns - not_faulty, most_faulty);
  EXPECT_GE(sigma_within_30_percent, least_within);
}

}  // namespace
}  // namespace insdiag::engine
