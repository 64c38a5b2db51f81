// A unit's history as pure functions: the repeatability and trend of one
// parameter against closed forms, their calibration on seeded simulated
// histories, and what the unit's own trend does to its diagnosis.
#include "insdiag/kb/unit_history.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <absl/strings/str_cat.h>

#include <cmath>
#include <numbers>
#include <random>

#include "evidence_reports.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::kb {
namespace {

using testing::Identified;
using testing::Ins2000;
using testing::Nominal;
using testing::NominalReport;
using ::testing::HasSubstr;

std::vector<HistoryPoint> Points(const std::vector<double>& days, const std::vector<double>& values, double se) {
  std::vector<HistoryPoint> out;
  for (std::size_t i = 0; i < days.size(); ++i) out.push_back({days[i], values[i], se});
  return out;
}

// Student's t two-sided tail in closed form on 1, 2 and 3 degrees of freedom
// (Abramowitz & Stegun 26.7.3 and 26.7.4).
double StudentClosedForm(double t, int dof) {
  const double a = std::abs(t);
  switch (dof) {
    case 1: return 1.0 - 2.0 / std::numbers::pi * std::atan(a);
    case 2: return 1.0 - a / std::sqrt(2.0 + a * a);
    default: {
      const double theta = std::atan(a / std::sqrt(3.0));
      return 1.0 - 2.0 / std::numbers::pi * (theta + std::sin(theta) * std::cos(theta));
    }
  }
}

TEST(UnitHistoryStatisticsTest, StudentTailMatchesClosedFormsOnOneTwoAndThreeDegreesOfFreedom) {
  for (int dof : {1, 2, 3}) {
    for (double t : {0.0, 0.3, 1.0, 2.5, 7.0, -4.0, 40.0}) {
      EXPECT_NEAR(StudentTwoSidedPValue(t, dof), StudentClosedForm(t, dof), 1e-12) << "t " << t << " dof " << dof;
    }
  }
  // Many degrees of freedom: the normal tail.
  EXPECT_NEAR(StudentTwoSidedPValue(1.96, 1e6), 2.0 * engine::stats::NormalCdf(-1.96), 1e-6);
}

TEST(UnitHistoryStatisticsTest, RunToRunRepeatabilityIsTheSampleSdWithItsChiSquareInterval) {
  const auto points = Points({0, 1, 2, 3, 4}, {1, 2, 3, 4, 5}, 0.5);
  const ParameterStatistics s = ParameterStatisticsOf(points, false, HistoryOptions());
  EXPECT_EQ(s.count, 5);
  EXPECT_DOUBLE_EQ(s.mean, 3.0);
  const double sd = std::sqrt(10.0 / 4.0);
  EXPECT_NEAR(s.run_to_run_sd, sd, 1e-12);
  // χ² quantiles on 4 degrees of freedom at 0.975 and 0.025 (tabled: 11.1433, 0.484419).
  EXPECT_NEAR(s.run_to_run_sd_low, sd * std::sqrt(4.0 / 11.143287), 1e-5);
  EXPECT_NEAR(s.run_to_run_sd_high, sd * std::sqrt(4.0 / 0.4844186), 1e-5);
  EXPECT_NEAR(s.rms_std_error, 0.5, 1e-12);
  EXPECT_FALSE(s.turn_on_to_turn_on_sd.has_value());
}

TEST(UnitHistoryStatisticsTest, TurnOnToTurnOnRepeatabilityRemovesTheIdentificationError) {
  // Equal SEs σ: DerSimonian–Laird's τ² reduces to s² − σ².
  const auto points = Points({0, 1, 2, 3, 4}, {1, 2, 3, 4, 5}, 1.0);
  const ParameterStatistics s = ParameterStatisticsOf(points, true, HistoryOptions());
  ASSERT_TRUE(s.turn_on_to_turn_on_sd.has_value());
  EXPECT_NEAR(*s.turn_on_to_turn_on_sd, std::sqrt(2.5 - 1.0), 1e-12);
  // SEs larger than the scatter explain all of it.
  const auto noisy = Points({0, 1, 2, 3, 4}, {1, 2, 3, 4, 5}, 3.0);
  EXPECT_EQ(ParameterStatisticsOf(noisy, true, HistoryOptions()).turn_on_to_turn_on_sd, 0.0);
  EXPECT_TRUE(IsTurnOnBias("gyro_turn_on_bias.x"));
  EXPECT_TRUE(IsTurnOnBias("acc_turn_on_bias.z"));
  EXPECT_FALSE(IsTurnOnBias("gyro_scale_factor.x"));
  EXPECT_FALSE(IsTurnOnBias("gyro_bias_gm.x.sigma"));
}

// Residuals r = c·(+1, −1, 0, −1, +1) at t = 0..4 are orthogonal to 1 and t:
// the fit returns the line exactly, with σ_b = σ/√10 and χ² = 4c²/σ².
std::vector<HistoryPoint> LineWithResiduals(double intercept, double slope, double c, double se) {
  const double pattern[] = {1, -1, 0, -1, 1};
  std::vector<HistoryPoint> out;
  for (int i = 0; i < 5; ++i) out.push_back({double(i), intercept + slope * i + c * pattern[i], se});
  return out;
}

TEST(UnitHistoryStatisticsTest, WeightedTrendMatchesTheClosedFormWhenTheSesExplainTheScatter) {
  const TrendFit fit = FitTrend(LineWithResiduals(2.0, 0.05, 0.1, 0.1), HistoryOptions());
  ASSERT_TRUE(fit.fitted);
  EXPECT_TRUE(fit.weighted);
  EXPECT_NEAR(fit.slope_per_day, 0.05, 1e-12);
  EXPECT_NEAR(fit.intercept, 2.0, 1e-12);
  EXPECT_NEAR(fit.slope_std_error_per_day, 0.1 / std::sqrt(10.0), 1e-12);
  EXPECT_NEAR(fit.chi_square, 4.0, 1e-9);
  EXPECT_EQ(fit.degrees_of_freedom, 3);
  EXPECT_NEAR(fit.scatter_p_value, engine::stats::ChiSquareSurvival(4.0, 3), 1e-12);
  EXPECT_FALSE(fit.excess_scatter);
  EXPECT_EQ(fit.birge_ratio, 1.0);
  const double z = 0.05 / (0.1 / std::sqrt(10.0));
  EXPECT_NEAR(fit.p_value, 2.0 * engine::stats::NormalCdf(-z), 1e-12);
}

TEST(UnitHistoryStatisticsTest, ExcessScatterInflatesTheSlopesErrorByTheBirgeRatioAndTestsWithStudent) {
  const TrendFit fit = FitTrend(LineWithResiduals(2.0, 0.05, 0.3, 0.1), HistoryOptions());
  ASSERT_TRUE(fit.fitted);
  EXPECT_NEAR(fit.chi_square, 36.0, 1e-9);
  EXPECT_TRUE(fit.excess_scatter);
  EXPECT_NEAR(fit.birge_ratio, std::sqrt(12.0), 1e-12);
  const double se = 0.1 / std::sqrt(10.0) * std::sqrt(12.0);
  EXPECT_NEAR(fit.slope_std_error_per_day, se, 1e-12);
  EXPECT_NEAR(fit.p_value, StudentClosedForm(0.05 / se, 3), 1e-12);
}

TEST(UnitHistoryStatisticsTest, WithoutStandardErrorsTheTrendIsOrdinaryLeastSquares) {
  const TrendFit fit = FitTrend(LineWithResiduals(2.0, 0.05, 0.1, 0.0), HistoryOptions());
  ASSERT_TRUE(fit.fitted);
  EXPECT_FALSE(fit.weighted);
  // σ_b² = (Σr²/ν)/Σ(t − t̄)² = (0.04/3)/10.
  const double se = std::sqrt(0.04 / 3.0 / 10.0);
  EXPECT_NEAR(fit.slope_std_error_per_day, se, 1e-12);
  EXPECT_NEAR(fit.p_value, StudentClosedForm(0.05 / se, 3), 1e-12);
  // One value in every run, without SEs: no trend, whatever the rounding.
  const TrendFit constant = FitTrend(Points({0, 3.3, 7.1, 9.9}, {4.84813681109536e-08, 4.84813681109536e-08,
                                                                        4.84813681109536e-08, 4.84813681109536e-08},
                                                    0.0),
                                             HistoryOptions());
  EXPECT_GT(constant.p_value, 0.01);
  EXPECT_FALSE(FitTrend(Points({0, 1}, {1, 2}, 0.1), HistoryOptions()).fitted);
  EXPECT_FALSE(FitTrend(Points({3, 3, 3}, {1, 2, 3}, 0.1), HistoryOptions()).fitted);
}

// On seeded simulated histories of a stable parameter the trend's p-value is
// uniform and the repeatability interval covers the true σ as often as its
// confidence says; with a genuine drift the test finds it.
TEST(UnitHistoryStatisticsTest, SimulatedStableHistoriesKeepTheTestsLevelAndTheIntervalsCoverage) {
  std::mt19937_64 rng(20261126);
  std::normal_distribution<double> unit(0.0, 1.0);
  constexpr int kHistories = 4000;
  constexpr double kSigma = 0.2;
  int rejected = 0, covered = 0;
  for (int h = 0; h < kHistories; ++h) {
    std::vector<HistoryPoint> points;
    for (int i = 0; i < 8; ++i) points.push_back({7.0 * i + 3.0 * unit(rng) * 0.1, 5.0 + kSigma * unit(rng), kSigma});
    const ParameterStatistics s = ParameterStatisticsOf(points, false, HistoryOptions());
    rejected += s.trend->p_value < 0.05;
    covered += s.run_to_run_sd_low <= kSigma && kSigma <= s.run_to_run_sd_high;
  }
  // Binomial(4000, 0.05): sd 0.0034.
  EXPECT_NEAR(static_cast<double>(rejected) / kHistories, 0.05, 0.012);
  EXPECT_NEAR(static_cast<double>(covered) / kHistories, 0.95, 0.012);
  int found = 0;
  for (int h = 0; h < 200; ++h) {
    std::vector<HistoryPoint> points;
    for (int i = 0; i < 8; ++i) points.push_back({7.0 * i, 5.0 + 0.02 * 7.0 * i + kSigma * unit(rng), kSigma});
    found += FitTrend(points, HistoryOptions()).p_value < 0.01;
  }
  // z = 0.02·√2058/0.2 ≈ 4.5 against 2.58: a power of about 0.97.
  EXPECT_GE(found, 180);
}

// --- The unit's own trend in its diagnosis -------------------------------

// A history of `runs` runs a week apart: every identified parameter of the
// nominal report scattering by its SE around nominal (seeded), and
// `drifting` growing linearly from `start` to `end` × nominal.
std::vector<ParameterHistory> History(int runs, const std::string& drifting, double start, double end,
                                     std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::vector<ParameterHistory> out;
  const v1::AnalysisReport nominal = NominalReport();
  for (const auto& p : nominal.identified()) {
    ParameterHistory& h = out.emplace_back();
    h.name = p.name();
    h.unit = p.unit();
    std::vector<HistoryPoint> points;
    for (int i = 0; i < runs; ++i) {
      const double factor = p.name() == drifting ? start + (end - start) * i / (runs - 1) : 1.0;
      const double value = p.value() * factor;
      const double se = p.std_error() / p.value() * value;
      points.push_back({7.0 * i, value + se * unit(rng), se});
      RunParameterPoint& point = h.points.emplace_back();
      point.days = points.back().days;
      point.value = points.back().value;
      point.std_error = se;
    }
    h.statistics = ParameterStatisticsOf(points, false, HistoryOptions());
  }
  return out;
}

Diagnosis DiagnoseWithHistory(const v1::AnalysisReport& report, const std::vector<ParameterHistory>* history) {
  const auto& f = Ins2000();
  Evidence evidence = EvidenceFromReport(FindingsOf(report), f.unit_type, f.settings);
  if (history != nullptr) {
    for (auto& t : TrendEvidence(*history, f.settings)) evidence.terms.push_back(std::move(t));
  }
  return Diagnose(evidence, f.modes, f.settings, {});
}

std::size_t RankOf(const Diagnosis& d, const std::string& module) {
  for (std::size_t i = 0; i < d.candidates.size(); ++i) {
    if (d.candidates[i].module == module) return i;
  }
  return d.candidates.size();
}

double ModuleProbability(const Diagnosis& d, const std::string& module) {
  return d.candidates.at(RankOf(d, module)).probability;
}

TEST(UnitHistoryDiagnosisTest, AGrowingDriftOverTheUnitsRunsRanksItsGyroHigherThanTheLastRunAlone) {
  const std::string sigma = "gyro_bias_gm.x.sigma";
  // The last run alone: σ at 1.6 × nominal, ±12 %: suspicious, not conclusive.
  v1::AnalysisReport report = NominalReport();
  Identified(report, sigma)->set_value(1.6 * Nominal(sigma));
  Identified(report, sigma)->set_std_error(0.12 * 1.6 * Nominal(sigma));
  const Diagnosis alone = DiagnoseWithHistory(report, nullptr);
  const auto history = History(10, sigma, 0.8, 1.6, 11);
  const auto trends = TrendEvidence(history, Ins2000().settings);
  ASSERT_EQ(trends.size(), 1u);
  EXPECT_EQ(trends[0].trend_of, sigma);
  EXPECT_GT(trends[0].x, 0.0);
  const Diagnosis with_history = DiagnoseWithHistory(report, &history);
  EXPECT_LT(RankOf(with_history, "gyro.x"), RankOf(alone, "gyro.x")) << ToProto(with_history).DebugString();
  EXPECT_EQ(RankOf(with_history, "gyro.x"), 0);
  EXPECT_GT(ModuleProbability(with_history, "gyro.x"), ModuleProbability(alone, "gyro.x"));
  // The diagnosis says why.
  bool explained = false;
  for (const auto& line : with_history.candidates[0].evidence) {
    explained = explained || (line.find(sigma + ": trend over the unit's 10 runs") != std::string::npos);
  }
  EXPECT_TRUE(explained) << ToProto(with_history).DebugString();
}

TEST(UnitHistoryDiagnosisTest, AStableUnitsHistoryLeavesItsDiagnosisUnchanged) {
  const v1::AnalysisReport report = NominalReport();
  const auto history = History(10, "", 1.0, 1.0, 12);
  EXPECT_TRUE(TrendEvidence(history, Ins2000().settings).empty());
  const Diagnosis alone = DiagnoseWithHistory(report, nullptr);
  const Diagnosis with_history = DiagnoseWithHistory(report, &history);
  ASSERT_EQ(alone.hypotheses.size(), with_history.hypotheses.size());
  for (std::size_t i = 0; i < alone.hypotheses.size(); ++i) {
    EXPECT_EQ(alone.hypotheses[i].failure_mode, with_history.hypotheses[i].failure_mode);
    EXPECT_EQ(alone.hypotheses[i].probability, with_history.hypotheses[i].probability);
  }
}

TEST(UnitHistoryDiagnosisTest, SettingsWithoutATrendModelTakeNoEvidenceFromTheHistory) {
  DiagnosisSettings settings = Ins2000().settings;
  settings.trend_z_spread = 0.0;
  EXPECT_TRUE(TrendEvidence(History(10, "gyro_bias_gm.x.sigma", 0.8, 1.6, 11), settings).empty());
}

}  // namespace
}  // namespace insdiag::kb
