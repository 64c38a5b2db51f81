#include "insdiag/api/report_codec.h"

#include <gtest/gtest.h>

#include <limits>
#include <set>

#include "insdiag/api/json.h"

namespace insdiag::api {
namespace {

// A candidate no test measured reaches API clients flagged as such, and an
// unknown standard error (infinite in the engine) as 0, which JSON can carry.
TEST(ReportCodec, UntestedCandidateIsFlaggedAndItsUnknownErrorIsFinite) {
  engine::AnalysisReport report;
  engine::EffectCandidate untested;
  untested.name = "gyro_bias_second_order.z";
  untested.source = "LIKELIHOOD";
  untested.tested = false;
  untested.std_error = std::numeric_limits<double>::infinity();
  untested.note = "not tested on this model: a constant term is significant";
  engine::EffectCandidate tested;
  tested.name = "gyro_scale_factor.z";
  tested.source = "SCORE";
  tested.estimate = 2e-4;
  tested.std_error = 2e-5;
  report.effect_candidates = {untested, tested};
  const v1::AnalysisReport out = ToProto(report, engine::ErrorModel{});
  ASSERT_EQ(out.effect_candidates_size(), 2);
  EXPECT_TRUE(out.effect_candidates(0).not_tested());
  EXPECT_EQ(out.effect_candidates(0).std_error(), 0.0);
  EXPECT_EQ(out.effect_candidates(0).note(), untested.note);
  EXPECT_FALSE(out.effect_candidates(1).not_tested());
  EXPECT_EQ(out.effect_candidates(1).std_error(), 2e-5);
}


// What the engine decided reaches API clients as records: the kind, its
// test, what it rejected, and the note the report's notes carry for it.
TEST(ReportCodec, DecisionsCarryTheirKindTestAndNote) {
  engine::Decision d;
  d.kind = engine::DecisionKind::kDriftsOverCandidate;
  d.subjects = {"gyro_bias_gm.x.sigma", "gyro_bias_gm.x.tau"};
  d.statistic = -115.5;
  d.adopted = true;
  d.rejected = {{"gyro_scale_factor.z", -4.1}};
  engine::AnalysisReport report;
  report.decisions = {d};
  const v1::AnalysisReport out = ToProto(report, engine::ErrorModel{});
  ASSERT_EQ(out.decisions_size(), 1);
  const v1::Decision& carried = out.decisions(0);
  EXPECT_EQ(carried.kind(), v1::Decision::DRIFTS_OVER_CANDIDATE);
  EXPECT_EQ(carried.subjects_size(), 2);
  EXPECT_TRUE(carried.adopted());
  EXPECT_EQ(carried.statistic(), -115.5);
  EXPECT_FALSE(carried.has_p_value());  // none was weighed: absent, not 0
  ASSERT_EQ(carried.rejected_size(), 1);
  EXPECT_EQ(carried.rejected(0).name(), "gyro_scale_factor.z");
  EXPECT_EQ(carried.note(), engine::RenderNote(d));
  const auto json = ToJson(carried, /*pretty=*/false);
  ASSERT_TRUE(json.ok()) << json.status();
  EXPECT_NE(json->find("\"kind\":\"DRIFTS_OVER_CANDIDATE\""), std::string::npos) << *json;
}

// Every kind of decision has its own name in the report.
TEST(ReportCodec, EveryDecisionKindHasItsOwnName) {
  engine::AnalysisReport report;
  for (int k = 0; k <= static_cast<int>(engine::DecisionKind::kAPrioriModel); ++k) {
    engine::Decision d;
    d.kind = static_cast<engine::DecisionKind>(k);
    report.decisions.push_back(d);
  }
  const v1::AnalysisReport out = ToProto(report, engine::ErrorModel{});
  std::set<int> kinds;
  for (const v1::Decision& d : out.decisions()) {
    EXPECT_NE(d.kind(), v1::Decision::KIND_UNSPECIFIED);
    kinds.insert(d.kind());
  }
  EXPECT_EQ(kinds.size(), report.decisions.size());
}

engine::ParameterEstimate FilterConstant(std::string name, double std_error, double prior_std, double correlation,
                                         std::string correlated_with = "") {
  engine::ParameterEstimate p;
  p.name = std::move(name);
  p.value = 1e-4;
  p.std_error = std_error;
  p.method = engine::EstimationMethod::kFilterState;
  p.unit = std::string("1");  // not operator=(const char*): GCC 12 -O3 warns falsely of an overlap there
  p.prior_std = prior_std;
  p.max_correlation = correlation;
  p.correlated_with = std::move(correlated_with);
  return p;
}

// Each identified parameter carries whether the run tells it and why not, as
// engine::ObservableByRun judges it; an estimate with nothing to judge it by
// (an Allan term) carries no verdict.
TEST(ReportCodec, IdentifiedParametersCarryWhetherTheRunTellsThem) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  engine::AnalysisReport report;
  report.identified = {
      FilterConstant("acc_turn_on_bias.x", 3e-4, 3e-2, 0.16, "gyro_turn_on_bias.y"),
      FilterConstant("acc_scale_factor.x", 4e-2, kInf, 0.08, "acc_turn_on_bias.x"),
      FilterConstant("acc_scale_factor.z", 2e-3, 3e-3, 0.99996, "acc_turn_on_bias.z"),
      FilterConstant("gyro_turn_on_bias.z", 4.7e-5, 5.8e-5, -0.42, "gyro_turn_on_bias.x"),
  };
  engine::ParameterEstimate allan;
  allan.name = "gyro_arw.x";
  allan.value = 1e-6;
  allan.std_error = 1e-8;
  allan.method = engine::EstimationMethod::kAllan;
  report.identified.push_back(allan);
  const v1::AnalysisReport out = ToProto(report, engine::ErrorModel{});
  ASSERT_EQ(out.identified_size(), 5);
  EXPECT_EQ(out.identified(0).observability(), v1::IdentifiedParameter::OBSERVABLE);
  EXPECT_EQ(out.identified(0).observability_note(), "");
  EXPECT_EQ(out.identified(1).observability(), v1::IdentifiedParameter::NOT_EXCITED);
  EXPECT_EQ(out.identified(1).observability_note(), "the test never excited it");
  EXPECT_EQ(out.identified(2).observability(), v1::IdentifiedParameter::INSEPARABLE);
  EXPECT_EQ(out.identified(2).observability_note(), "only with acc_turn_on_bias.z (correlation +1.000)");
  EXPECT_EQ(out.identified(3).observability(), v1::IdentifiedParameter::WEAKLY_DETERMINED);
  EXPECT_EQ(out.identified(3).observability_note(), "standard error 0.81 of the prior's");
  EXPECT_EQ(out.identified(4).observability(), v1::IdentifiedParameter::OBSERVABILITY_UNSPECIFIED);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(out.identified(i).observability() == v1::IdentifiedParameter::OBSERVABLE,
              engine::ObservableByRun(report.identified[static_cast<size_t>(i)]))
        << out.identified(i).name();
  }
  // On the API's JSON, by the enum's name.
  auto json = ToJson(out.identified(2), /*pretty=*/false);
  ASSERT_TRUE(json.ok()) << json.status();
  EXPECT_NE(json->find(R"("observability":"INSEPARABLE")"), std::string::npos) << *json;
}

// A report stored before the field reads back with no verdict, not as
// "not observable": proto3's default is the enum's UNSPECIFIED.
TEST(ReportCodec, AReportStoredBeforeTheObservabilityFieldReadsAsNotJudged) {
  v1::AnalysisReport stored;
  ASSERT_TRUE(FromJson(R"({"identified": [{"name": "acc_scale_factor.z", "value": 1e-4, "stdError": 2e-3,
                                           "method": "FILTER", "unit": "1"}]})",
                       &stored)
                  .ok());
  ASSERT_EQ(stored.identified_size(), 1);
  EXPECT_EQ(stored.identified(0).observability(), v1::IdentifiedParameter::OBSERVABILITY_UNSPECIFIED);
  EXPECT_EQ(stored.identified(0).observability_note(), "");
  auto model = IdentifiedModelOf(stored);
  ASSERT_TRUE(model.ok()) << model.status();
  ASSERT_EQ(model->identified.size(), 1u);
  EXPECT_EQ(model->identified[0].name, "acc_scale_factor.z");
}

}  // namespace
}  // namespace insdiag::api
