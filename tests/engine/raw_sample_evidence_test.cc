// The still segments' raw samples as evidence beside the navigation errors
// (finder/raw_sample_evidence.h): a constant-bias candidate they refute is
// not ranked, at the level the test states and no more often.
#include "insdiag/engine/finder/raw_sample_evidence.h"

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

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

}  // namespace
}  // namespace insdiag::engine
