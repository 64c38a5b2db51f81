// The still segments' raw samples as evidence beside the navigation errors
// (finder/raw_sample_evidence.h): a constant-bias candidate they refute is
// not ranked, at the level the test states and no more often.
#include "insdiag/engine/finder/raw_sample_evidence.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "insdiag/engine/filter/epoch_run.h"
#include "insdiag/engine/finder/fault_findings.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine {
namespace {

constexpr double kAlpha = 0.01;

EffectTerm TermOf(std::string_view selector) {
  auto terms = ParseEffectSelector(std::string(selector));
  EXPECT_TRUE(terms.ok()) << terms.status();
  return terms->front();
}

// The six axes' constants of a still run, every one at `std_error`.
std::vector<RawSampleConstant> StillRunConstants(double gyro_std_error, double acc_std_error) {
  std::vector<RawSampleConstant> out;
  for (int a = 0; a < 3; ++a) out.push_back({Sensor::kGyro, a, 0.0, gyro_std_error});
  for (int a = 0; a < 3; ++a) out.push_back({Sensor::kAccelerometer, a, 0.0, acc_std_error});
  return out;
}

TEST(RawSampleConstants, RefuteAVerticalGyroBiasFarBeyondTheirBound) {
  // A 0.1 °/h unit on a still level table, an accelerometer ramp unmodelled:
  // the navigation errors offer a z gyro bias of 3.6 °/h (1.75e-5 ± 4.1e-6
  // rad/s); 37 minutes of still samples bound it to 2e-7 rad/s.
  const std::vector<RawSampleConstant> constants = StillRunConstants(2e-7, 1e-5);
  std::string note;
  EXPECT_TRUE(RefutedByRawSamples(TermOf("gyro_turn_on_bias.z"), -1.75e-5, 4.1e-6, constants,
                                  kAlpha, &note));
  EXPECT_NE(note.find("refuted by the raw samples"), std::string::npos) << note;
  // The same estimate where the raw samples hold the same bias stands.
  std::vector<RawSampleConstant> agreeing = constants;
  agreeing[2].bias = -1.6e-5;
  EXPECT_FALSE(RefutedByRawSamples(TermOf("gyro_turn_on_bias.z"), -1.75e-5, 4.1e-6, agreeing,
                                   kAlpha, nullptr));
}

TEST(RawSampleConstants, SayNothingOfTermsTheyDoNotMeasure) {
  const std::vector<RawSampleConstant> constants = StillRunConstants(2e-7, 1e-5);
  // A scale factor, a step and a walk are not the still mean's constant.
  for (const char* selector : {"gyro_scale_factor.z", "gyro_bias_step.z", "gyro_bias_rw.z"}) {
    EXPECT_FALSE(RefutedByRawSamples(TermOf(selector), 1.0, 1e-9, constants, kAlpha, nullptr))
        << selector;
  }
  // No constant of the axis: no verdict.
  const std::vector<RawSampleConstant> accelerometers_only(constants.begin() + 3, constants.end());
  EXPECT_FALSE(RefutedByRawSamples(TermOf("gyro_turn_on_bias.z"), -1.75e-5, 4.1e-6,
                                   accelerometers_only, kAlpha, nullptr));
}

TEST(RawSampleConstants, ComparableOnlyForSensorsTheModelHoldsNoDeterministicEffectOf) {
  RawSampleEvidence evidence;
  evidence.constants = StillRunConstants(2e-7, 1e-5);
  ErrorModel model;
  model.effects.push_back({.term = TermOf("gyro_bias_rw.x")});
  EXPECT_EQ(RawConstantsComparable(evidence, model).size(), 6u)
      << "a random effect leaves the mean's meaning";
  model.effects.push_back({.term = TermOf("acc_scale_factor.z")});
  const std::vector<RawSampleConstant> kept = RawConstantsComparable(evidence, model);
  ASSERT_EQ(kept.size(), 3u);
  for (const RawSampleConstant& c : kept) EXPECT_EQ(c.sensor, Sensor::kGyro);
}

TEST(RawSampleConstants, RefuteATrueConstantAtMostAtTheStatedLevel) {
  // Both estimates of the same six constants, each with its own noise: the
  // share of runs where any of the six is refuted is at most α (Bonferroni),
  // and near it for independent estimates.
  std::mt19937_64 rng(20261128);
  std::normal_distribution<double> unit_normal;
  std::uniform_real_distribution<double> log_ratio(-3.0, 3.0);
  const std::vector<EffectTerm> terms = {
      TermOf("gyro_turn_on_bias.x"), TermOf("gyro_turn_on_bias.y"), TermOf("gyro_turn_on_bias.z"),
      TermOf("acc_turn_on_bias.x"),  TermOf("acc_turn_on_bias.y"),  TermOf("acc_turn_on_bias.z")};
  constexpr int kRuns = 20000;
  int runs_with_a_refutation = 0;
  for (int run = 0; run < kRuns; ++run) {
    std::vector<RawSampleConstant> constants = StillRunConstants(0.0, 0.0);
    std::vector<double> estimates, std_errors;
    for (size_t i = 0; i < terms.size(); ++i) {
      const double truth = unit_normal(rng);
      const double raw_se = std::exp(log_ratio(rng)), nav_se = std::exp(log_ratio(rng));
      constants[i].bias = truth + raw_se * unit_normal(rng);
      constants[i].std_error = raw_se;
      estimates.push_back(truth + nav_se * unit_normal(rng));
      std_errors.push_back(nav_se);
    }
    bool any = false;
    for (size_t i = 0; i < terms.size(); ++i) {
      any |= RefutedByRawSamples(terms[i], estimates[i], std_errors[i], constants, kAlpha, nullptr);
    }
    runs_with_a_refutation += any ? 1 : 0;
  }
  // Bonferroni over six independent tests: 1 − (1 − α/6)⁶ ≈ 0.00998.
  const double expected = 1.0 - std::pow(1.0 - kAlpha / 6.0, 6.0);
  const double band = 4.0 * std::sqrt(expected * (1.0 - expected) / kRuns);
  EXPECT_NEAR(static_cast<double>(runs_with_a_refutation) / kRuns, expected, band);
}

// A run of `seconds` one-second update intervals, and the scan's fit of
// `selector` over its onsets from the 60th with a flat score: the navigation
// errors see the fault with information `information` at every onset and
// a likelihood ratio of `statistic` there.
struct ScannedRun {
  EpochRun run;
  OnsetFit fit;
};

ScannedRun FlatScan(std::string_view selector, int seconds, double statistic, double information,
                    double p_value) {
  ScannedRun s;
  s.run.epochs.resize(static_cast<size_t>(seconds));
  for (int k = 0; k < seconds; ++k) {
    s.run.epochs[static_cast<size_t>(k)].start_s = k;
    s.run.epochs[static_cast<size_t>(k)].time_s = k + 1.0;
  }
  s.fit.term = TermOf(selector);
  s.fit.identifiable = true;
  s.fit.first_onset_epoch = 60;
  s.fit.statistic_by_onset.assign(static_cast<size_t>(seconds - 120), statistic);
  s.fit.statistic = statistic;
  s.fit.estimate = std::sqrt(statistic / information);
  s.fit.std_error = 1.0 / std::sqrt(information);
  s.fit.p_value = p_value;
  return s;
}

FaultScale AccelerometerNoise(double white_density, double drift_sigma, double drift_tau_s,
                              double run_end_s) {
  FaultScale scale;
  scale.white_noise_density.fill(white_density);
  scale.drift_sigma.fill(drift_sigma);
  scale.drift_tau_s.fill(drift_tau_s);
  scale.run_end_s = run_end_s;
  return scale;
}

TEST(RawSampleRamps, StandInForTheScansTermWhereTheyAreTheStrongerEvidence) {
  // A still table hides an accelerometer's ramp as a tilt the gyro's drift
  // explains: the scan's fit is flat (p 1), the samples' test is not.
  ScannedRun scanned = FlatScan("acc_bias_ramp.x", 2000, 2.0, 1e10, 1.0);
  std::vector<EffectCandidate> candidates = FaultCandidates({scanned.fit}, 12000);
  ASSERT_EQ(candidates.size(), 1u);
  candidates[0].correlated_with = {"gyro_bias_step.y"};
  const RawSampleChange ramp{
      Sensor::kAccelerometer, 0, Regressor::kRamp, 829.0, -2.06e-4, 60.0, 1e-6};
  const FaultScale scale = AccelerometerNoise(5e-4, 1e-2, 300.0, 2000.0);
  AddRawSampleFaultCandidates(candidates, {scanned.fit}, std::span(&ramp, 1), scanned.run, 12000,
                              scale, kAlpha);
  ASSERT_EQ(candidates.size(), 1u) << "one candidate per term";
  const EffectCandidate& c = candidates[0];
  EXPECT_EQ(c.source, "RAW");
  EXPECT_DOUBLE_EQ(c.estimate, -2.06e-4);
  EXPECT_NEAR(c.p_value, 6e-6, 1e-12) << "Bonferroni over the six channels";
  EXPECT_NEAR(c.statistic, 2.0, 1e-9) << "the navigation errors' 2Δℓ at the samples' onset";
  EXPECT_NEAR(c.predicted_delta_bic, -2.0 + std::log(12000.0), 1e-9);
  ASSERT_TRUE(c.onset_s.has_value());
  EXPECT_DOUBLE_EQ(*c.onset_s, 829.0);
  EXPECT_EQ(c.correlated_with, std::vector<std::string>{"gyro_bias_step.y"});
  EXPECT_TRUE(IsFaultCandidate(c));
  // The slope's error: white noise over the 1171 s after the onset, and the
  // drift as the walk K = σ √(2/τ).
  const double span_s = 2000.0 - 829.0, walk = 1e-2 * std::sqrt(2.0 / 300.0);
  EXPECT_NEAR(c.std_error,
              std::sqrt(12.0 * 5e-4 * 5e-4 / std::pow(span_s, 3) + 1.2 * walk * walk / span_s),
              1e-12);
}

TEST(RawSampleRamps, LeaveTheScansTermWhereItIsTheStrongerEvidence) {
  ScannedRun scanned = FlatScan("acc_bias_ramp.y", 3600, 190.0, 1e10, 1e-40);
  std::vector<EffectCandidate> candidates = FaultCandidates({scanned.fit}, 20000);
  const RawSampleChange ramp{
      Sensor::kAccelerometer, 1, Regressor::kRamp, 1319.0, 5.5e-6, 60.0, 1e-4};
  AddRawSampleFaultCandidates(candidates, {scanned.fit}, std::span(&ramp, 1), scanned.run, 20000,
                              AccelerometerNoise(5e-4, 1e-2, 300.0, 3600.0), kAlpha);
  ASSERT_EQ(candidates.size(), 1u);
  EXPECT_EQ(candidates[0].source, "GLR");
  // A finding of the scan that places the samples' change keeps its onset,
  // though the samples' p-value is smaller.
  std::vector<EffectCandidate> placed =
      FaultCandidates({FlatScan("acc_bias_ramp.y", 3600, 30.0, 1e10, 1e-5).fit}, 20000);
  placed[0].seen_in_raw_samples = true;
  const RawSampleChange clearer = {
      Sensor::kAccelerometer, 1, Regressor::kRamp, 1319.0, 5.5e-6, 60.0, 1e-9};
  AddRawSampleFaultCandidates(placed, {scanned.fit}, std::span(&clearer, 1), scanned.run, 20000,
                              AccelerometerNoise(5e-4, 1e-2, 300.0, 3600.0), kAlpha);
  EXPECT_EQ(placed[0].source, "GLR");
  // Nor is a jump of the ramp's axis that ramp, nor a ramp of another axis.
  const RawSampleChange jump{
      Sensor::kAccelerometer, 1, Regressor::kStep, 1319.0, 5.5e-3, 1.0, 1e-9, 5e-4};
  const RawSampleChange other_axis{
      Sensor::kAccelerometer, 2, Regressor::kRamp, 1319.0, 5.5e-6, 60.0, 1e-9};
  for (const RawSampleChange& change : {jump, other_axis}) {
    std::vector<EffectCandidate> weak =
        FaultCandidates({FlatScan("acc_bias_ramp.y", 3600, 1.0, 1e10, 1.0).fit}, 20000);
    AddRawSampleFaultCandidates(weak, {scanned.fit}, std::span(&change, 1), scanned.run, 20000,
                                AccelerometerNoise(5e-4, 1e-2, 300.0, 3600.0), kAlpha);
    ASSERT_EQ(weak.size(), 1u);
    EXPECT_EQ(weak[0].source, "GLR");
  }
}

TEST(RawSampleJumps, StandInForAStepTheNavigationErrorsShowThroughTheHeadingAlone) {
  // The eighth blind draw's run 439: a 1 °/h unit on a still table, its z
  // gyro stepping by 7.2e-5 rad/s at 697 s. The navigation errors see it
  // through the heading alone (2Δℓ 9, p 0.37 after Holm); the z gyro's
  // still samples jump by 6.4e-5 at 697 s, z 9.8.
  ScannedRun scanned = FlatScan("gyro_bias_step.z", 4800, 9.0, 1e10, 0.01);
  std::vector<EffectCandidate> candidates = FaultCandidates({scanned.fit}, 29000);
  const RawSampleChange jump{Sensor::kGyro, 2,     Regressor::kStep, 696.8, 6.38e-5, 6.4,
                             2e-16,         6.5e-6};
  FaultScale scale = AccelerometerNoise(1e-5, 4.85e-6, 300.0, 4800.0);
  AddRawSampleFaultCandidates(candidates, {scanned.fit}, std::span(&jump, 1), scanned.run, 29000,
                              scale, kAlpha);
  ASSERT_EQ(candidates.size(), 1u) << "one candidate per term";
  const EffectCandidate& c = candidates[0];
  EXPECT_EQ(c.source, "RAW");
  EXPECT_DOUBLE_EQ(c.estimate, 6.38e-5);
  EXPECT_DOUBLE_EQ(c.std_error, 6.5e-6)
      << "the samples' own scatter of the window means' difference";
  EXPECT_NEAR(c.p_value, 1.2e-15, 1e-27) << "Bonferroni over the six channels";
  EXPECT_NEAR(c.statistic, 9.0, 1e-9) << "the navigation errors' 2Δℓ at the samples' onset";
  ASSERT_TRUE(c.onset_s.has_value());
  EXPECT_DOUBLE_EQ(*c.onset_s, 696.8);
  ASSERT_TRUE(c.size_in_drift_sigma.has_value());
  EXPECT_NEAR(*c.size_in_drift_sigma, 6.38e-5 / 4.85e-6, 1e-9) << "a step's size, not its reach";
  EXPECT_NE(c.note.find("a jump the still segments' raw samples show at 697 s"), std::string::npos)
      << c.note;
  // A jump the test did not find clear of noise (p 1) is no candidate.
  std::vector<EffectCandidate> untested = FaultCandidates({scanned.fit}, 29000);
  RawSampleChange unclear = jump;
  unclear.p_value = 1.0;
  AddRawSampleFaultCandidates(untested, {scanned.fit}, std::span(&unclear, 1), scanned.run, 29000,
                              scale, kAlpha);
  EXPECT_EQ(untested[0].source, "GLR");
}

}  // namespace
}  // namespace insdiag::engine
