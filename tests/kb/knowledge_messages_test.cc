// The knowledge base's terms and the API's messages carry the same facts:
// every built-in unit type and failure mode survives the trip through the
// domain types unchanged, and a report's findings hold what the diagnosis
// reads of it.
#include "insdiag/kb/knowledge_messages.h"

#include <google/protobuf/util/message_differencer.h>
#include <gtest/gtest.h>

#include <algorithm>

#include "evidence_reports.h"
#include "insdiag/api/unit_types.h"
#include "insdiag/kb/failure_mode_catalogue.h"

namespace insdiag::kb {
namespace {

using google::protobuf::util::MessageDifferencer;

TEST(KnowledgeMessagesTest, EveryBuiltInUnitTypeAndFailureModeRoundTripsUnchanged) {
  int modes_seen = 0;
  for (const v1::UnitType& unit_type : api::BuiltinUnitTypes()) {
    EXPECT_TRUE(MessageDifferencer::Equals(ToProto(UnitTypeOf(unit_type)), unit_type)) << unit_type.name();
  }
  for (const v1::FailureModeCatalogue& catalogue : BuiltinFailureModeCatalogues()) {
    auto modes = ExpandCatalogue(catalogue);
    ASSERT_TRUE(modes.ok()) << modes.status();
    for (const v1::FailureMode& mode : *modes) {
      EXPECT_TRUE(MessageDifferencer::Equals(ToProto(FailureModeOf(mode)), mode)) << mode.name();
      ++modes_seen;
    }
  }
  EXPECT_GT(modes_seen, 0);
}

TEST(KnowledgeMessagesTest, ScalesAndDirectionsReadBackFromTheirStoredNames) {
  for (Scale scale : {Scale::kLogRatio, Scale::kTolerance, Scale::kZ}) {
    EXPECT_EQ(ScaleNamed(ScaleName(scale)), scale);
  }
  for (Direction direction : {Direction::kUp, Direction::kDown, Direction::kEither}) {
    EXPECT_EQ(DirectionNamed(DirectionName(direction)), direction);
  }
  EXPECT_FALSE(ScaleNamed("ratio").has_value());
  EXPECT_FALSE(DirectionNamed("SIDEWAYS").has_value());
}

TEST(KnowledgeMessagesTest, FindingsHoldWhatTheDiagnosisReadsOfAReport) {
  v1::AnalysisReport report = testing::NominalReport();
  report.set_verdict(v1::AnalysisReport::OPERABLE);
  v1::IdentifiedParameter* sigma = testing::Identified(report, "gyro_bias_gm.x.sigma");
  ASSERT_NE(sigma, nullptr);
  sigma->set_jointly_with("gyro_bias_gm.x.tau");
  sigma->set_log_correlation(-0.4);
  v1::EffectCandidate* step = report.add_effect_candidates();
  step->set_name("gyro_bias_step.y");
  step->set_onset_s(1200.0);
  step->set_onset_std_s(30.0);
  step->set_source("ONSET_SCAN");
  report.mutable_model()->add_effects("gyro_bias_rw.z");
  v1::DiscoveryStep* added = report.add_discovery();
  added->set_step(1);
  added->set_effect("gyro_bias_rw.z");
  added->set_p_value(1e-6);

  const ReportFindings findings = FindingsOf(report);
  EXPECT_EQ(findings.verdict, engine::Verdict::kOperable);
  ASSERT_EQ(findings.identified.size(), static_cast<std::size_t>(report.identified_size()));
  ASSERT_EQ(findings.candidates.size(), static_cast<std::size_t>(report.effect_candidates_size()));
  bool paired = false;
  for (const IdentifiedFinding& p : findings.identified) {
    if (p.name != "gyro_bias_gm.x.sigma") {
      EXPECT_FALSE(p.log_correlation.has_value()) << p.name << ": a correlation the report does not state";
      continue;
    }
    paired = true;
    EXPECT_EQ(p.jointly_with, "gyro_bias_gm.x.tau");
    EXPECT_EQ(p.log_correlation, -0.4);
    EXPECT_EQ(p.method, "ACF");
  }
  EXPECT_TRUE(paired);
  const CandidateFinding& onset = findings.candidates.back();
  EXPECT_EQ(onset.onset_s, 1200.0);
  EXPECT_EQ(onset.onset_std_s, 30.0);
  EXPECT_EQ(onset.source, "ONSET_SCAN");
  EXPECT_FALSE(findings.candidates.front().onset_s.has_value());
  EXPECT_EQ(findings.model_effects, std::vector<std::string>{"gyro_bias_rw.z"});
  ASSERT_EQ(findings.discovery.size(), 1u);
  EXPECT_EQ(findings.discovery[0].effect, "gyro_bias_rw.z");

  report.clear_verdict();
  EXPECT_FALSE(FindingsOf(report).verdict.has_value()) << "an unstated verdict is not read as GOOD";
}

// The engine's record that it set the unit type aside reaches the
// diagnosis, which says its evidence reads a unit of another class.
TEST(KnowledgeMessagesTest, AUnitTypeSetAsideByTheAnalysisIsReadAndTheDiagnosisSaysSo) {
  v1::AnalysisReport report = testing::NominalReport();
  EXPECT_FALSE(FindingsOf(report).unit_type_set_aside.has_value());
  const auto notes_naming_it = [](const Diagnosis& d) {
    return std::count_if(d.notes.begin(), d.notes.end(),
                         [](const std::string& n) { return n.find("nominal model aside") != std::string::npos; });
  };
  EXPECT_EQ(notes_naming_it(testing::DiagnoseReport(report)), 0);

  v1::Decision* aside = report.add_decisions();
  aside->set_kind(v1::Decision::UNIT_TYPE_SET_ASIDE);
  aside->add_subjects("gyro_x");
  v1::Decision::Measure* tau = aside->add_measures();
  tau->set_name("tau_s");
  tau->set_value(10.0);
  v1::Decision::Measure* ratio = aside->add_measures();
  ratio->set_name("ratio");
  ratio->set_value(1200.0);
  const ReportFindings findings = FindingsOf(report);
  ASSERT_TRUE(findings.unit_type_set_aside.has_value());
  EXPECT_EQ(findings.unit_type_set_aside->channel, "gyro_x");
  EXPECT_EQ(findings.unit_type_set_aside->tau_s, 10.0);
  EXPECT_EQ(findings.unit_type_set_aside->ratio, 1200.0);
  EXPECT_EQ(notes_naming_it(testing::DiagnoseReport(report)), 1);
}

TEST(KnowledgeMessagesTest, ADiagnosisReadsAsTheApiShowsIt) {
  const Diagnosis diagnosis = testing::DiagnoseReport(testing::NominalReport());
  const v1::Diagnosis shown = ToProto(diagnosis);
  ASSERT_EQ(shown.candidates_size(), static_cast<int>(diagnosis.candidates.size()));
  ASSERT_EQ(shown.hypotheses_size(), static_cast<int>(diagnosis.hypotheses.size()));
  ASSERT_EQ(shown.evidence_size(), static_cast<int>(diagnosis.evidence.size()));
  for (std::size_t i = 0; i < diagnosis.candidates.size(); ++i) {
    const int k = static_cast<int>(i);
    EXPECT_EQ(shown.candidates(k).module(), diagnosis.candidates[i].module);
    EXPECT_EQ(shown.candidates(k).probability(), diagnosis.candidates[i].probability);
    EXPECT_EQ(shown.candidates(k).evidence_size(), static_cast<int>(diagnosis.candidates[i].evidence.size()));
  }
  for (std::size_t i = 0; i < diagnosis.evidence.size(); ++i) {
    EXPECT_EQ(shown.evidence(static_cast<int>(i)).scale(), ScaleName(diagnosis.evidence[i].scale));
  }
}

}  // namespace
}  // namespace insdiag::kb
