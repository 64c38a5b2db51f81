#include "analysis_codec.h"

#include <gtest/gtest.h>

#include "insdiag/kb/knowledge_messages.h"

namespace insdiag::server {
namespace {

v1::AnalysisSpec SpecWithEverything() {
  v1::AnalysisSpec spec;
  spec.mutable_model()->add_effects("gyro_bias_step.x");
  auto* p = spec.mutable_model()->add_parameters();
  p->set_name("gyro_bias_gm.x.sigma");
  p->set_value(1e-4);
  p->set_unit("rad/s");
  spec.mutable_baseline()->add_effects("acc_bias_gm.x");
  spec.set_discover(true);
  spec.set_base_analysis("analyses/0a0a0a0a-0000-0000-0000-000000000001");
  return spec;
}

v1::AnalysisReport ReportWithRows() {
  v1::AnalysisReport report;
  report.set_verdict(v1::AnalysisReport::OPERABLE);
  report.set_nis_mean(1.25);
  report.set_log_likelihood(-321.5);
  report.set_aic(650.0);
  report.set_bic(700.0);
  auto* sigma = report.add_identified();
  sigma->set_name("gyro_bias_gm.x.sigma");
  sigma->set_value(2e-4);
  sigma->set_std_error(1e-5);
  sigma->set_method(v1::IdentifiedParameter::ML);
  sigma->set_a_priori(1e-4);
  auto* tau = report.add_identified();
  tau->set_name("gyro_bias_gm.x.tau");
  tau->set_value(300.0);
  tau->set_std_error(20.0);
  tau->set_method(v1::IdentifiedParameter::ACF);
  for (auto* c : {report.add_effect_candidates(), report.add_family_candidates()}) {
    c->set_name("gyro_bias_step.x");
    c->set_family("gyro_bias_step");
    c->set_source("score");
    c->set_statistic(9.5);
    c->set_degrees_of_freedom(2);
    c->set_p_value(0.002);
    c->set_p_value_holm(0.01);
    c->set_estimate(3e-5);
    c->set_std_error(1e-5);
    c->set_unit("rad/s");
    c->set_identifiable(true);
    c->set_predicted_delta_aic(-5.5);
  }
  for (const char* name : {"lat", "vel_n"}) {
    auto* c = report.add_channels();
    c->set_name(name);
    c->set_rms(0.5);
    c->set_fit_percent(98.0);
    c->set_nis_mean(1.1);
    c->set_whiteness_p_value(0.3);
    c->set_sample_count(1200);
  }
  auto* f = report.add_fault_intervals();
  f->set_channel("vel_e");
  f->set_start_s(10.0);
  f->set_end_s(12.5);
  f->set_kind(v1::FaultInterval::ABRUPT);
  f->set_peak_statistic(40.0);
  report.add_fault_intervals()->set_channel("lat");  // no kind
  return report;
}

TEST(AnalysisCodec, AnAnalysisKeepsEveryFieldAndItsSpecAndReportBytes) {
  const v1::AnalysisReport report = ReportWithRows();
  kb::Analysis analysis;
  analysis.name = "analyses/0a0a0a0a-0000-0000-0000-000000000002";
  analysis.run = "runs/0b0b0b0b-0000-0000-0000-000000000003";
  analysis.unit = "units/INS-0001";
  analysis.encoded_spec = EncodedSpec(SpecWithEverything());
  analysis.state = kb::AnalysisState::kFailed;
  analysis.progress_fraction = 0.75;
  analysis.progress_stage = "identification";
  analysis.error = kb::AnalysisError{13, "the engine failed"};
  analysis.attempts = 2;
  analysis.create_time = absl::FromUnixMicros(1'700'000'000'123'456);
  analysis.update_time = absl::FromUnixMicros(-1);
  analysis.report = kb::StoredReport{EncodedReport(report), kb::ReportRows()};
  const v1::Analysis message = ToProto(analysis);
  EXPECT_EQ(message.name(), analysis.name);
  EXPECT_EQ(message.run(), analysis.run);
  EXPECT_EQ(message.unit(), "units/INS-0001");
  const v1::AnalysisSpec spec = SpecWithEverything();
  EXPECT_EQ(message.model().SerializeAsString(), spec.model().SerializeAsString());
  EXPECT_TRUE(message.has_baseline());
  EXPECT_EQ(message.baseline().SerializeAsString(), spec.baseline().SerializeAsString());
  EXPECT_TRUE(message.discover());
  EXPECT_EQ(message.base_analysis(), spec.base_analysis());
  EXPECT_EQ(message.state(), v1::Analysis::FAILED);
  EXPECT_EQ(message.progress().fraction(), 0.75);
  EXPECT_EQ(message.progress().stage(), "identification");
  EXPECT_EQ(message.error().code(), 13);
  EXPECT_EQ(message.error().message(), "the engine failed");
  EXPECT_EQ(message.attempts(), 2);
  EXPECT_EQ(message.create_time().seconds(), 1'700'000'000);
  EXPECT_EQ(message.create_time().nanos(), 123'456'000);
  EXPECT_EQ(message.update_time().seconds(), -1);
  EXPECT_EQ(message.update_time().nanos(), 999'999'000);
  EXPECT_EQ(message.report().SerializeAsString(), report.SerializeAsString());
}

TEST(AnalysisCodec, UnsetStaysUnset) {
  kb::Analysis analysis;
  analysis.state = kb::AnalysisState::kQueued;
  const v1::Analysis message = ToProto(analysis);
  EXPECT_EQ(message.state(), v1::Analysis::QUEUED);
  EXPECT_FALSE(message.has_error());
  EXPECT_FALSE(message.has_report());
  EXPECT_FALSE(message.has_baseline());
  EXPECT_TRUE(message.has_model());     // as the store has always answered
  EXPECT_TRUE(message.has_progress());  // likewise
  EXPECT_EQ(ToProto(kb::AnalysisState::kUnspecified), v1::Analysis::STATE_UNSPECIFIED);

  const kb::ReportRows rows = ReportRowsOf(v1::AnalysisReport());
  EXPECT_FALSE(rows.verdict.has_value());
  const kb::ReportRows with_rows = ReportRowsOf(ReportWithRows());
  EXPECT_FALSE(with_rows.identified[1].a_priori.has_value());
  EXPECT_FALSE(with_rows.fault_intervals[1].kind.has_value());
}

TEST(AnalysisCodec, TheRowsCarryEveryQueriedField) {
  const kb::ReportRows rows = ReportRowsOf(ReportWithRows());
  EXPECT_EQ(rows.verdict, engine::Verdict::kOperable);
  EXPECT_EQ(rows.nis_mean, 1.25);
  EXPECT_EQ(rows.log_likelihood, -321.5);
  EXPECT_EQ(rows.aic, 650.0);
  EXPECT_EQ(rows.bic, 700.0);
  ASSERT_EQ(rows.identified.size(), 2U);
  EXPECT_EQ(rows.identified[0].name, "gyro_bias_gm.x.sigma");
  EXPECT_EQ(rows.identified[0].value, 2e-4);
  EXPECT_EQ(rows.identified[0].std_error, 1e-5);
  EXPECT_EQ(rows.identified[0].method, "ML");
  EXPECT_EQ(rows.identified[0].a_priori, 1e-4);
  ASSERT_EQ(rows.effect_candidates.size(), 1U);
  ASSERT_EQ(rows.family_candidates.size(), 1U);
  const kb::EffectCandidateRow& c = rows.effect_candidates[0];
  EXPECT_EQ(c.name, "gyro_bias_step.x");
  EXPECT_EQ(c.family, "gyro_bias_step");
  EXPECT_EQ(c.source, "score");
  EXPECT_EQ(c.statistic, 9.5);
  EXPECT_EQ(c.degrees_of_freedom, 2);
  EXPECT_EQ(c.p_value, 0.002);
  EXPECT_EQ(c.p_value_holm, 0.01);
  EXPECT_EQ(c.estimate, 3e-5);
  EXPECT_EQ(c.std_error, 1e-5);
  EXPECT_EQ(c.unit, "rad/s");
  EXPECT_TRUE(c.identifiable);
  EXPECT_EQ(c.predicted_delta_aic, -5.5);
  ASSERT_EQ(rows.channels.size(), 2U);
  EXPECT_EQ(rows.channels[1].channel, "vel_n");
  EXPECT_EQ(rows.channels[1].rms, 0.5);
  EXPECT_EQ(rows.channels[1].fit_percent, 98.0);
  EXPECT_EQ(rows.channels[1].nis_mean, 1.1);
  EXPECT_EQ(rows.channels[1].whiteness_p_value, 0.3);
  EXPECT_EQ(rows.channels[1].sample_count, 1200);
  ASSERT_EQ(rows.fault_intervals.size(), 2U);
  EXPECT_EQ(rows.fault_intervals[0].channel, "vel_e");
  EXPECT_EQ(rows.fault_intervals[0].start_s, 10.0);
  EXPECT_EQ(rows.fault_intervals[0].end_s, 12.5);
  EXPECT_EQ(rows.fault_intervals[0].kind, engine::FaultKind::kAbrupt);
  EXPECT_EQ(rows.fault_intervals[0].peak_statistic, 40.0);
}

TEST(AnalysisCodec, AReportRebuiltFromItsRowsHasTheirFieldsAndSaysSo) {
  const v1::AnalysisReport original = ReportWithRows();
  const v1::AnalysisReport rebuilt = RebuiltReport(ReportRowsOf(original), "");
  // What the rows keep, field for field; each channel's unit from its name.
  v1::AnalysisReport expected;
  expected.set_verdict(original.verdict());
  expected.set_nis_mean(original.nis_mean());
  expected.set_log_likelihood(original.log_likelihood());
  expected.set_aic(original.aic());
  expected.set_bic(original.bic());
  expected.mutable_model();
  *expected.mutable_identified() = original.identified();
  *expected.mutable_effect_candidates() = original.effect_candidates();
  *expected.mutable_family_candidates() = original.family_candidates();
  *expected.mutable_channels() = original.channels();
  expected.mutable_channels(0)->set_unit("m");
  expected.mutable_channels(1)->set_unit("m/s");
  *expected.mutable_fault_intervals() = original.fault_intervals();
  expected.add_notes(
      "rebuilt from the knowledge base's rows: this analysis was stored without its full report (e.g. generated "
      "fleet history), so only the verdict, headline figures, identified parameters, effect candidates, channel "
      "metrics and fault intervals are present");
  EXPECT_EQ(rebuilt.SerializeAsString(), expected.SerializeAsString()) << rebuilt.DebugString();
  EXPECT_TRUE(rebuilt.has_model());
  EXPECT_FALSE(rebuilt.identified(1).has_a_priori());

  kb::StoredReport stored;
  stored.rows = ReportRowsOf(original);
  EXPECT_EQ(ReportOf(stored, "").SerializeAsString(), rebuilt.SerializeAsString());
}

TEST(AnalysisCodec, TheFindingsOfRowsAreThoseOfTheReportRebuiltFromThem) {
  const kb::ReportRows rows = ReportRowsOf(ReportWithRows());
  auto decoded = kb::DecodeReportFindings(EncodedReport(RebuiltReport(rows, "")));
  ASSERT_TRUE(decoded.ok());
  const kb::ReportFindings from_rows = kb::FindingsOfRows(rows);
  EXPECT_EQ(from_rows.verdict, decoded->verdict);
  ASSERT_EQ(from_rows.identified.size(), decoded->identified.size());
  for (std::size_t i = 0; i < from_rows.identified.size(); ++i) {
    EXPECT_EQ(from_rows.identified[i].name, decoded->identified[i].name);
    EXPECT_EQ(from_rows.identified[i].value, decoded->identified[i].value);
    EXPECT_EQ(from_rows.identified[i].std_error, decoded->identified[i].std_error);
    EXPECT_EQ(from_rows.identified[i].unit, decoded->identified[i].unit);
    EXPECT_EQ(from_rows.identified[i].method, decoded->identified[i].method);
    EXPECT_EQ(from_rows.identified[i].jointly_with, decoded->identified[i].jointly_with);
    EXPECT_EQ(from_rows.identified[i].log_correlation, decoded->identified[i].log_correlation);
  }
  ASSERT_EQ(from_rows.candidates.size(), decoded->candidates.size());
  const kb::CandidateFinding& a = from_rows.candidates[0];
  const kb::CandidateFinding& b = decoded->candidates[0];
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.estimate, b.estimate);
  EXPECT_EQ(a.std_error, b.std_error);
  EXPECT_EQ(a.unit, b.unit);
  EXPECT_EQ(a.statistic, b.statistic);
  EXPECT_EQ(a.degrees_of_freedom, b.degrees_of_freedom);
  EXPECT_EQ(a.p_value, b.p_value);
  EXPECT_EQ(a.p_value_holm, b.p_value_holm);
  EXPECT_EQ(a.source, b.source);
  EXPECT_EQ(a.identifiable, b.identifiable);
  EXPECT_EQ(a.not_tested, b.not_tested);
  EXPECT_EQ(a.onset_s, b.onset_s);
  EXPECT_EQ(a.onset_std_s, b.onset_std_s);
  EXPECT_EQ(from_rows.model_effects, decoded->model_effects);
  EXPECT_TRUE(from_rows.discovery.empty());
  EXPECT_TRUE(decoded->discovery.empty());

  kb::ReportRows unknown_method;
  unknown_method.identified.push_back(kb::IdentifiedParameterRow{"x", 1.0, 0.1, "GUESSED", std::nullopt});
  EXPECT_EQ(kb::FindingsOfRows(unknown_method).identified[0].method, "METHOD_UNSPECIFIED");
}

TEST(AnalysisCodec, TheDecoderReadsAReportsFindings) {
  const v1::AnalysisReport report = ReportWithRows();
  auto findings = kb::DecodeReportFindings(EncodedReport(report));
  ASSERT_TRUE(findings.ok());
  EXPECT_EQ(findings->verdict, kb::FindingsOf(report).verdict);
  EXPECT_EQ(findings->identified.size(), 2U);
  EXPECT_EQ(findings->candidates.size(), 1U);
}

TEST(AnalysisCodec, ResidualPointsKeepEveryField) {
  const std::vector<kb::ResidualPoint> points = {{"lat", 1.5, 10.0, 9.5, 0.5, 0.9}, {"vel_d", 2.0, 1.0, 1.25, -0.25, 0.3}};
  const v1::ResidualSeriesChunk chunk = ToProto(points);
  ASSERT_EQ(chunk.points_size(), 2);
  EXPECT_EQ(chunk.points(1).channel(), "vel_d");
  EXPECT_EQ(chunk.points(1).t(), 2.0);
  EXPECT_EQ(chunk.points(1).measured(), 1.0);
  EXPECT_EQ(chunk.points(1).predicted(), 1.25);
  EXPECT_EQ(chunk.points(1).residual(), -0.25);
  EXPECT_EQ(chunk.points(1).sigma3(), 0.3);
  EXPECT_EQ(ToProto(std::span<const kb::ResidualPoint>()).points_size(), 0);
}

TEST(AnalysisCodec, TheSpecRoundTripsThroughItsBytes) {
  const v1::AnalysisSpec spec = SpecWithEverything();
  EXPECT_EQ(SpecOf(EncodedSpec(spec)).SerializeAsString(), spec.SerializeAsString());
  EXPECT_EQ(SpecOf("").SerializeAsString(), "");
}

}  // namespace
}  // namespace insdiag::server
