// A unit's history on a real PostgreSQL: analyses of one unit over several
// weeks stored through the stores, read back in time order with the
// statistics of kb/unit_history.h, paged; and the diagnosis of the last run
// with and without the unit's own history.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

#include "analysis_codec.h"
#include "evidence_reports.h"
#include "insdiag/kb/catalogue_store.h"
#include "insdiag/kb/diagnose_analysis.h"
#include "insdiag/kb/diagnosis_store.h"
#include "insdiag/kb/catalogue_data.h"
#include "insdiag/kb/unit_history.h"
#include "insdiag/kb/unit_history_store.h"
#include "support/database_fixture.h"
#include "support/stored_history.h"

namespace insdiag::kb {
namespace {

using ::testing::HasSubstr;

constexpr char kSigma[] = "gyro_bias_gm.x.sigma";
constexpr char kTurnOn[] = "gyro_turn_on_bias.x";
constexpr double kDaysBetweenRuns = 7.0;

class UnitHistoryStoreTest : public insdiag::testing::DatabaseTest {
 protected:
  void SetUp() override {
    DatabaseTest::SetUp();
    if (IsSkipped() || HasFatalFailure()) return;
    CatalogueStore catalogue(pool());
    ASSERT_TRUE(SeedBuiltinCatalogues(catalogue).ok());
  }

  std::string StoreRunAndAnalysis(const std::string& serial, double days, const v1::AnalysisReport& report,
                                  std::string* run_id = nullptr) {
    return insdiag::testing::StoreAnalysedRun(pool(), serial, days, report, run_id);
  }
  std::string AnalyseRun(const std::string& run_id, const v1::AnalysisReport& report) {
    return insdiag::testing::AnalyseStoredRun(pool(), run_id, report);
  }

  // The nominal report with σ of gyro x at `sigma_factor` × nominal (±12 %)
  // and a turn-on bias of gyro x of `bias_rad_s` ± `bias_se_rad_s`.
  static v1::AnalysisReport Report(double sigma_factor, double bias_rad_s, double bias_se_rad_s) {
    v1::AnalysisReport report = testing::NominalReport();
    auto* sigma = testing::Identified(report, kSigma);
    sigma->set_value(sigma_factor * testing::Nominal(kSigma));
    sigma->set_std_error(0.12 * sigma->value());
    auto* bias = report.add_identified();
    bias->set_name(kTurnOn);
    bias->set_value(bias_rad_s);
    bias->set_std_error(bias_se_rad_s);
    bias->set_method(v1::IdentifiedParameter::STATIC);
    return report;
  }
};

TEST_F(UnitHistoryStoreTest, ReturnsTheRunsInTestOrderWithEachParametersPointsAndStatistics) {
  std::mt19937_64 rng(42);
  const double bias_tolerance = testing::Tolerance(kTurnOn);
  std::normal_distribution<double> turn_on(0.2 * bias_tolerance, 0.3 * bias_tolerance);
  const double bias_se = 0.05 * bias_tolerance;
  std::vector<HistoryPoint> sigma_points(6), bias_points(6);
  std::vector<std::string> runs(6);
  // Stored out of test order: the history sorts by the test date.
  for (int i : {3, 0, 5, 1, 4, 2}) {
    const double days = kDaysBetweenRuns * i;
    const double factor = 0.8 + 0.16 * i;
    const double bias = turn_on(rng);
    StoreRunAndAnalysis("INS-H1", days, Report(factor, bias, bias_se), &runs[i]);
    sigma_points[i] = {days, factor * testing::Nominal(kSigma), 0.12 * factor * testing::Nominal(kSigma)};
    bias_points[i] = {days, bias, bias_se};
  }
  // A second analysis of the first run, later: it stands for that run.
  bias_points[0].value = turn_on(rng);
  AnalyseRun(runs[0], Report(0.8, bias_points[0].value, bias_se));

  UnitHistoryStore store(pool());
  UnitHistoryQuery query;
  query.unit = "units/INS-H1";
  auto history = store.Get(query);
  ASSERT_TRUE(history.ok()) << history.status();
  EXPECT_EQ(history->unit_type, "unitTypes/INS-2000");
  EXPECT_EQ(history->run_count, 6);
  EXPECT_EQ(history->analysed_run_count, 6);
  ASSERT_EQ(history->runs.size(), 6u);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(history->runs[i].run, "runs/" + runs[i]);
  ASSERT_EQ(history->runs[0].analyses.size(), 2u);
  EXPECT_FALSE(history->runs[0].analyses[0].counted);
  EXPECT_TRUE(history->runs[0].analyses[1].counted);

  const ParameterHistory* sigma = nullptr;
  const ParameterHistory* bias = nullptr;
  for (const auto& p : history->parameters) {
    if (p.name == kSigma) sigma = &p;
    if (p.name == kTurnOn) bias = &p;
  }
  ASSERT_NE(sigma, nullptr);
  ASSERT_NE(bias, nullptr);
  EXPECT_EQ(sigma->unit, "rad/s");
  EXPECT_FALSE(sigma->turn_on_bias);
  EXPECT_TRUE(bias->turn_on_bias);
  ASSERT_EQ(sigma->points.size(), 6u);
  for (int i = 0; i < 6; ++i) {
    EXPECT_NEAR(sigma->points[i].days, kDaysBetweenRuns * i, 1e-9);
    EXPECT_EQ(sigma->points[i].run, "runs/" + runs[i]);
  }
  // The statistics are those of the points as stored.
  const ParameterStatistics expected = ParameterStatisticsOf(sigma_points, false, HistoryOptions());
  ASSERT_TRUE(sigma->statistics.trend.has_value() && expected.trend.has_value());
  EXPECT_NEAR(sigma->statistics.trend->slope_per_day, expected.trend->slope_per_day, 1e-20);
  EXPECT_NEAR(sigma->statistics.run_to_run_sd, expected.run_to_run_sd, 1e-20);
  EXPECT_LT(sigma->statistics.trend->p_value, 1e-3);
  const ParameterStatistics bias_expected = ParameterStatisticsOf(bias_points, true, HistoryOptions());
  ASSERT_TRUE(bias->statistics.turn_on_to_turn_on_sd.has_value());
  ASSERT_TRUE(bias_expected.turn_on_to_turn_on_sd.has_value());
  EXPECT_NEAR(*bias->statistics.turn_on_to_turn_on_sd, *bias_expected.turn_on_to_turn_on_sd, 1e-18);
  EXPECT_NEAR(bias->statistics.run_to_run_sd, bias_expected.run_to_run_sd, 1e-18);
  EXPECT_GT(*bias->statistics.turn_on_to_turn_on_sd, 0.0);
}

TEST_F(UnitHistoryStoreTest, PagesTheRunsAndFiltersTheParametersAndRefusesWhatItCannotRead) {
  for (int i = 0; i < 5; ++i) StoreRunAndAnalysis("INS-H2", kDaysBetweenRuns * i, Report(1.0, 0.0, 1e-7));
  UnitHistoryStore store(pool());
  UnitHistoryQuery query;
  query.unit = "units/INS-H2";
  query.page_size = 3;
  query.parameters.push_back(kSigma);
  auto first = store.Get(query);
  ASSERT_TRUE(first.ok()) << first.status();
  EXPECT_EQ(first->runs.size(), 3u);
  ASSERT_FALSE(first->next_page_token.empty());
  ASSERT_EQ(first->parameters.size(), 1u);
  EXPECT_EQ(first->parameters[0].points.size(), 5u);  // the statistics cover every run
  query.page_token = first->next_page_token;
  auto second = store.Get(query);
  ASSERT_TRUE(second.ok()) << second.status();
  EXPECT_EQ(second->runs.size(), 2u);
  EXPECT_TRUE(second->next_page_token.empty());
  EXPECT_NE(second->runs[0].run, first->runs[2].run);

  query.unit = "units/NOPE";
  query.page_token.clear();
  EXPECT_EQ(store.Get(query).status(), absl::NotFoundError("units/NOPE does not exist"));
  query.unit = "units/INS-H2";
  query.confidence = 1.5;
  EXPECT_EQ(store.Get(query).status(),
            absl::InvalidArgumentError("confidence: must lie strictly between 0 and 1"));
  query.confidence = 0.0;
  query.page_token = "not-a-token";
  EXPECT_EQ(store.Get(query).status().code(), absl::StatusCode::kInvalidArgument);
}

double ModuleProbability(const v1::Diagnosis& d, const std::string& module) {
  for (const auto& c : d.candidates()) {
    if (c.module() == module) return c.probability();
  }
  return 0.0;
}

TEST_F(UnitHistoryStoreTest, AUnitsGrowingDriftStrengthensItsGyroWhileAStableHistoryChangesNothing) {
  DiagnosisStore diagnoses(pool(), DecodeReportFindings);
  const v1::AnalysisReport last = Report(1.6, 0.0, 1e-7);
  // The last run alone, on a unit without history.
  auto alone = testing::DiagnoseStored(diagnoses, StoreRunAndAnalysis("INS-ALONE", 0.0, last));
  ASSERT_TRUE(alone.ok()) << alone.status();
  // The same last run after five runs with σ growing towards it.
  std::string final_analysis;
  for (int i = 0; i < 6; ++i) {
    final_analysis = StoreRunAndAnalysis("INS-DRIFT", kDaysBetweenRuns * i, i < 5 ? Report(0.8 + 0.16 * i, 0.0, 1e-7) : last);
  }
  auto drifting = testing::DiagnoseStored(diagnoses, final_analysis);
  ASSERT_TRUE(drifting.ok()) << drifting.status();
  EXPECT_GT(ModuleProbability(*drifting, "gyro.x"), ModuleProbability(*alone, "gyro.x"));
  EXPECT_EQ(drifting->candidates(0).module(), "gyro.x") << drifting->DebugString();
  EXPECT_THAT(drifting->notes(), ::testing::Contains(HasSubstr("significant trends in gyro_bias_gm.x.sigma")));
  bool shown = false;
  for (const auto& e : drifting->evidence()) shown = shown || e.name() == std::string(kSigma) + ".trend";
  EXPECT_TRUE(shown);

  // A stable unit: six runs at nominal scattering within their SEs (seeded), then the same last run.
  std::mt19937_64 rng(7);
  std::normal_distribution<double> scatter(0.0, 0.12);
  std::string stable_last;
  for (int i = 0; i < 6; ++i) {
    stable_last = StoreRunAndAnalysis("INS-STABLE", kDaysBetweenRuns * i, i < 5 ? Report(1.0 + scatter(rng), 0.0, 1e-7) : last);
  }
  auto stable = testing::DiagnoseStored(diagnoses, stable_last);
  ASSERT_TRUE(stable.ok()) << stable.status();
  ASSERT_EQ(stable->hypotheses_size(), alone->hypotheses_size());
  for (int i = 0; i < stable->hypotheses_size(); ++i) {
    EXPECT_EQ(stable->hypotheses(i).failure_mode(), alone->hypotheses(i).failure_mode());
    EXPECT_DOUBLE_EQ(stable->hypotheses(i).probability(), alone->hypotheses(i).probability());
  }
  EXPECT_THAT(stable->notes(), ::testing::Contains(HasSubstr("no parameter trends significantly")));
}

}  // namespace
}  // namespace insdiag::kb
