// The verdict in plain words (engine/plain_words.h): at most five lines, the
// verdict first, each finding with what the raw samples read either side of
// it, and what to do last.
#include "insdiag/engine/plain_words.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <utility>

namespace insdiag::engine {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

constexpr double kRadSPerDegH = std::numbers::pi / 180.0 / 3600.0;

// Ten minutes at 10 Hz whose gyro x reads 1 °/h, then 3 °/h from 300 s.
BenchRun StepRun() {
  BenchRun run;
  for (int k = 1; k <= 6000; ++k) {
    ImuSample s;
    s.t_s = 0.1 * k;
    s.gyro_rad_s.x() = (s.t_s < 300.0 ? 1.0 : 3.0) * kRadSPerDegH;
    s.acc_mps2.z() = -9.81;
    run.samples.push_back(s);
  }
  return run;
}

EffectCandidate Step(double p_value_holm) {
  EffectCandidate c;
  c.name = "gyro_bias_step.x";
  c.family = "gyro_bias_step";
  c.estimate = 2.0 * kRadSPerDegH;
  c.std_error = 0.1 * kRadSPerDegH;
  c.unit = "rad/s";
  c.p_value = c.p_value_holm = p_value_holm;
  c.onset_s = 300.0;
  return c;
}

// The samples as recorded, read back from the run the analysis changed: a
// spike repaired by the screening, then a constant removed from every sample.
TEST(RecordedSamples, PutBackTheRepairedSpikeAndTheRemovedConstant) {
  const BenchRun recorded = StepRun();
  BenchRun worked_on = recorded;
  SampleOutlier spike;
  spike.sample = 1234;
  spike.sensor_channel = 0;
  spike.time_s = worked_on.samples[spike.sample].t_s;
  spike.value = 500.0 * kRadSPerDegH;
  worked_on.samples[spike.sample].gyro_rad_s.x() = spike.value;
  BenchRun as_recorded_with_spike = worked_on;
  spike.replacement = 1.0 * kRadSPerDegH;
  worked_on.samples[spike.sample].gyro_rad_s.x() = spike.replacement;
  const Eigen::Vector3d removed_gyro(2.0 * kRadSPerDegH, 0.0, 0.0), removed_acc(0.0, 0.0, -9.8);
  for (ImuSample& s : worked_on.samples) {
    s.gyro_rad_s -= removed_gyro;
    s.acc_mps2 -= removed_acc;
  }
  const SampleOutlier spikes[] = {spike};
  const RecordedSamples samples{worked_on, removed_gyro, removed_acc, spikes};
  const RecordedSamples as_recorded{as_recorded_with_spike, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), {}};
  for (int channel : {0, 5}) {
    for (auto [from_s, to_s] : {std::pair{60.0, 180.0}, std::pair{100.0, 160.0}, std::pair{290.0, 350.0}}) {
      EXPECT_NEAR(samples.Mean(channel, from_s, to_s), as_recorded.Mean(channel, from_s, to_s), 1e-12)
          << "channel " << channel << " over [" << from_s << ", " << to_s << ")";
    }
  }
  // The window holding the spike reads it as recorded: 499 °/h above the rest over 600 samples.
  EXPECT_NEAR(samples.Mean(0, 100.0, 160.0) / kRadSPerDegH, 1.0 + 499.0 / 600.0, 1e-9);
  EXPECT_TRUE(std::isnan(samples.Mean(0, 700.0, 800.0)));
}

TEST(PlainWords, AFaultyUnitsStepIsStatedWithTheRawMinuteMeansAndTheModuleToCheck) {
  AnalysisReport report;
  report.verdict = Verdict::kFaulty;
  report.effect_candidates = {Step(1e-9), Step(0.5)};
  const std::vector<std::string> lines = PlainWordsVerdict(report, StepRun(), 0.01);
  ASSERT_EQ(lines.size(), 3u);  // the verdict, the one significant finding, what to do
  EXPECT_THAT(lines[0], StartsWith("FAULTY: 1 sensor fault(s) found"));
  EXPECT_THAT(lines[1], HasSubstr("gyro x bias stepped by 2 °/h at 300 s"));
  EXPECT_THAT(lines[1], HasSubstr("read 1.0 °/h in the minute before and 3.0 °/h in the minute after, a change of 2 °/h"));
  EXPECT_THAT(lines[2], HasSubstr("check the gyro x module"));
}

// Seven findings on six axes: three are stated, one an axis, and the lines
// stay five.
TEST(PlainWords, NeverMoreThanFiveLinesAndAGoodUnitNeedsNothing) {
  AnalysisReport faulty;
  faulty.verdict = Verdict::kFaulty;
  for (const char* name : {"gyro_bias_step.x", "gyro_bias_step.y", "gyro_bias_step.z", "acc_bias_step.x",
                           "acc_bias_step.y", "acc_bias_step.z", "gyro_bias_ramp.x"}) {
    EffectCandidate c = Step(1e-9);
    c.name = name;
    faulty.effect_candidates.push_back(c);
  }
  EXPECT_EQ(PlainWordsVerdict(faulty, StepRun(), 0.01).size(), static_cast<std::size_t>(kPlainWordsMaxLines));

  AnalysisReport good;
  good.verdict = Verdict::kGood;
  const std::vector<std::string> lines = PlainWordsVerdict(good, StepRun(), 0.01);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_THAT(lines[0], StartsWith("GOOD: "));
  EXPECT_THAT(lines[1], HasSubstr("nothing"));
}

// A unit whose drift the run's data took over its model's (the
// likelihood-ratio test of the model's drifts rejected them) is told so with
// the drift that departs, in °/h against the model's value; drifts against
// an Allan fit's values (no specification), or kept, say nothing of the unit.
TEST(PlainWords, DriftsTheDataTookOverTheModelsAreNamed) {
  ParameterEstimate sigma;
  sigma.name = "gyro_bias_gm.x.sigma";
  sigma.value = 0.03 * kRadSPerDegH;
  sigma.a_priori = 0.01 * kRadSPerDegH;
  sigma.ci95_low = 0.02 * kRadSPerDegH;
  sigma.ci95_high = 0.045 * kRadSPerDegH;
  ParameterEstimate within = sigma;  // a drift whose interval holds its model's value
  within.name = "gyro_bias_gm.y.sigma";
  within.ci95_low = 0.005 * kRadSPerDegH;
  Decision taken;
  taken.kind = DecisionKind::kDriftsIdentified;
  taken.subjects = {sigma.name, within.name};
  taken.statistic = 126.1;
  taken.degrees_of_freedom = 2;
  taken.level = 0.01;
  taken.adopted = true;
  AnalysisReport report;
  report.verdict = Verdict::kGood;
  report.identified = {sigma, within};
  report.decisions = {taken};
  std::vector<std::string> lines = PlainWordsVerdict(report, StepRun(), 0.01);
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_THAT(lines[1], HasSubstr("2Δℓ 126.1 against χ²(2) at 0.01"));
  EXPECT_THAT(lines[1], HasSubstr("gyro x drift σ 0.03 °/h against 0.01 °/h (3 ×)"));
  EXPECT_THAT(lines[1], ::testing::Not(HasSubstr("gyro y")));
  report.decisions.front().qualifiers = {"allan_fit_prior"};
  EXPECT_EQ(PlainWordsVerdict(report, StepRun(), 0.01).size(), 2u);
  report.decisions.front().qualifiers.clear();
  report.decisions.front().adopted = false;
  EXPECT_EQ(PlainWordsVerdict(report, StepRun(), 0.01).size(), 2u);
}

// A constant the model lacks is no fault: the plain words say what to add,
// the loop's next step.
TEST(PlainWords, AMissingConstantIsToBeAddedNotAModuleToCheck) {
  AnalysisReport report;
  report.verdict = Verdict::kOperable;
  EffectCandidate c = Step(1e-6);
  c.name = "acc_turn_on_bias.x";
  c.onset_s.reset();
  report.effect_candidates = {c};
  const std::vector<std::string> lines = PlainWordsVerdict(report, StepRun(), 0.01);
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_THAT(lines[1], HasSubstr("acc_turn_on_bias.x"));
  EXPECT_THAT(lines[2], HasSubstr("--add acc_turn_on_bias.x"));
  EXPECT_THAT(lines[2], ::testing::Not(HasSubstr("module")));
}

// A gradual failure no fault explains names where the filter puts it by the
// sensor, with the state's name for the engineer who reads the report on.
TEST(PlainWords, AGradualFailureIsLocalisedToItsSensor) {
  AnalysisReport report;
  report.verdict = Verdict::kFaulty;
  FaultInterval gradual;
  gradual.channel = "lat";
  gradual.kind = FaultKind::kGradual;
  gradual.start_s = 2.0;
  report.faults = {gradual};
  Localisation l;
  l.state = "acc_bias_gm.x";
  l.time_s = 18.0;
  l.p_value = 1e-9;
  report.localisation = {l};
  const std::vector<std::string> lines = PlainWordsVerdict(report, StepRun(), 0.01);
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_THAT(lines[0], StartsWith("FAULTY: the model fails gradually on lat from 2 s"));
  EXPECT_THAT(lines[1], HasSubstr("localises it to the accelerometer x (acc_bias_gm.x) at 18 s"));
}

// A run whose NIS lies outside its band with no interval: which way says
// whether the model is pessimistic (nothing to do on the unit) or the bench
// noisy, and the channels outside their own band say where.
TEST(PlainWords, AWholeRunOutsideItsBandSaysWhichWayAndWhere) {
  AnalysisReport report;
  report.verdict = Verdict::kOperable;
  report.nis_band_low = 0.9;
  report.nis_band_high = 1.1;
  const int updates = 300;  // five minutes of one-second updates a channel
  auto channel = [&](const char* name, double nis) {
    ChannelFit c;
    c.name = name;
    c.count = updates;
    c.nis_mean = nis;
    return c;
  };
  report.channels = {channel("lat", 0.35), channel("lon", 0.98), channel("vel_d", 0.6)};
  report.fit.nis_mean = 0.64;
  std::vector<std::string> lines = PlainWordsVerdict(report, StepRun(), 0.01);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_THAT(lines[0], HasSubstr("quieter than its model"));
  EXPECT_THAT(lines[0], HasSubstr("most on lat (NIS 0.35), vel_d (0.60)"));
  EXPECT_THAT(lines[0], ::testing::Not(HasSubstr("lon")));
  EXPECT_THAT(lines[1], HasSubstr("nothing on the unit"));

  report.channels = {channel("vel_n", 1.7), channel("lat", 1.02)};
  report.fit.nis_mean = 1.3;
  lines = PlainWordsVerdict(report, StepRun(), 0.01);
  EXPECT_THAT(lines[0], HasSubstr("noisier than its model"));
  EXPECT_THAT(lines[0], HasSubstr("most on vel_n (NIS 1.70)"));
  EXPECT_THAT(lines[1], HasSubstr("vibration or motion"));
}

// A unit whose model carries its warm-ups (the analysis took them to
// explain a failing start): the plain words say how it settles after
// power-up, in °/h or mg with each time constant, naming only the start
// values the run determines beyond 1.96 SE, and the verdict stays GOOD.
TEST(PlainWords, AWarmUpTheModelCarriesIsSaidHowTheUnitSettles) {
  AnalysisReport good;
  good.verdict = Verdict::kGood;
  good.model_effects = {"gyro_turn_on_bias.x", "gyro_warm_up.x@516", "acc_turn_on_bias.y", "acc_warm_up.y@518"};
  ParameterEstimate gyro;
  gyro.name = "gyro_warm_up.x";
  gyro.value = 186.0 * kRadSPerDegH;
  gyro.std_error = 30.0 * kRadSPerDegH;
  ParameterEstimate acc;  // 0.7 mg ± 36 mg: the run does not tell it
  acc.name = "acc_warm_up.y";
  acc.value = -0.007;
  acc.std_error = 0.36;
  good.identified = {gyro, acc};
  const std::vector<std::string> lines = PlainWordsVerdict(good, StepRun(), 0.01);
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_THAT(lines[0], StartsWith("GOOD: "));
  EXPECT_THAT(lines[1], HasSubstr("settles after power-up"));
  EXPECT_THAT(lines[1], HasSubstr("gyro x from 186 °/h with τ 516 s"));
  EXPECT_THAT(lines[1], ::testing::Not(HasSubstr("accelerometer")));
  EXPECT_THAT(lines[2], HasSubstr("nothing"));
}

}  // namespace
}  // namespace insdiag::engine
