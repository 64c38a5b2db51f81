#include "history_codec.h"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace insdiag::server {
namespace {

// The fields of `message` (and of every message inside it) left at their
// default: a field the codec forgot to carry shows up here.
void CollectUnsetFields(const google::protobuf::Message& message, const std::string& prefix,
                        std::vector<std::string>& unset) {
  const google::protobuf::Descriptor* descriptor = message.GetDescriptor();
  const google::protobuf::Reflection* reflection = message.GetReflection();
  for (int i = 0; i < descriptor->field_count(); ++i) {
    const google::protobuf::FieldDescriptor* field = descriptor->field(i);
    const std::string path = prefix + field->name();
    if (field->is_repeated()) {
      const int size = reflection->FieldSize(message, field);
      if (size == 0) unset.push_back(path);
      if (field->cpp_type() != google::protobuf::FieldDescriptor::CPPTYPE_MESSAGE) continue;
      for (int j = 0; j < size; ++j) {
        CollectUnsetFields(reflection->GetRepeatedMessage(message, field, j), path + ".", unset);
      }
    } else if (!reflection->HasField(message, field)) {
      unset.push_back(path);
    } else if (field->cpp_type() == google::protobuf::FieldDescriptor::CPPTYPE_MESSAGE) {
      CollectUnsetFields(reflection->GetMessage(message, field), path + ".", unset);
    }
  }
}

std::vector<std::string> UnsetFields(const google::protobuf::Message& message) {
  std::vector<std::string> unset;
  CollectUnsetFields(message, "", unset);
  return unset;
}

kb::TrendFit FittedTrend() {
  kb::TrendFit fit;
  fit.fitted = true;
  fit.weighted = true;
  fit.slope_per_day = 1.5e-9;
  fit.slope_std_error_per_day = 2.5e-10;
  fit.intercept = 4.8e-7;
  fit.p_value = 3.1e-4;
  fit.chi_square = 12.25;
  fit.degrees_of_freedom = 4;
  fit.scatter_p_value = 0.0156;
  fit.excess_scatter = true;
  fit.birge_ratio = 1.75;
  return fit;
}

// A history with every field of the message set to something other than its default.
kb::UnitHistory FullHistory() {
  kb::UnitHistory history;
  history.unit = "units/INS-H1";
  history.unit_type = "unitTypes/INS-2000";
  kb::HistoryRun& run = history.runs.emplace_back();
  run.run = "runs/6f0e2a1c-9d10-4f43-9a54-0b0e8a4e3a4b";
  run.test_time = absl::FromUnixMicros(1'767'600'000'123'456);
  run.duration_s = 3600.0;
  kb::HistoryAnalysis& analysis = run.analyses.emplace_back();
  analysis.analysis = "analyses/0b0e8a4e-3a4b-4f43-9a54-6f0e2a1c9d10";
  analysis.create_time = absl::FromUnixMicros(1'767'603'600'000'001);
  analysis.verdict = engine::Verdict::kOperable;
  analysis.unit_hours = 1234.5;
  analysis.counted = true;
  analysis.identified_count = 17;
  history.next_page_token = "bmV4dA==";
  kb::ParameterHistory& parameter = history.parameters.emplace_back();
  parameter.name = "gyro_turn_on_bias.x";
  parameter.unit = "rad/s";
  parameter.turn_on_bias = true;
  kb::RunParameterPoint& point = parameter.points.emplace_back();
  point.run = run.run;
  point.analysis = analysis.analysis;
  point.test_time = run.test_time;
  point.days = 7.25;
  point.value = 4.9e-7;
  point.std_error = 2.0e-8;
  parameter.statistics.count = 6;
  parameter.statistics.mean = 4.85e-7;
  parameter.statistics.run_to_run_sd = 3.0e-8;
  parameter.statistics.run_to_run_sd_low = 1.9e-8;
  parameter.statistics.run_to_run_sd_high = 7.4e-8;
  parameter.statistics.rms_std_error = 2.1e-8;
  parameter.statistics.turn_on_to_turn_on_sd = 2.2e-8;
  parameter.statistics.trend = FittedTrend();
  history.run_count = 7;
  history.analysed_run_count = 6;
  history.confidence = 0.9;
  history.notes.push_back("fewer than three runs with a succeeded analysis: no trend yet");
  return history;
}

TEST(HistoryCodec, AFullHistoryCarriesEveryFieldOfTheMessage) {
  const v1::UnitHistory message = ToProto(FullHistory());
  EXPECT_EQ(UnsetFields(message), std::vector<std::string>());
}

TEST(HistoryCodec, AHistoryKeepsItsValuesTimesAndVerdict) {
  const kb::UnitHistory history = FullHistory();
  const v1::UnitHistory message = ToProto(history);
  EXPECT_EQ(message.unit(), "units/INS-H1");
  EXPECT_EQ(message.unit_type(), "unitTypes/INS-2000");
  EXPECT_EQ(message.next_page_token(), "bmV4dA==");
  EXPECT_EQ(message.run_count(), 7);
  EXPECT_EQ(message.analysed_run_count(), 6);
  EXPECT_EQ(message.confidence(), 0.9);
  ASSERT_EQ(message.notes_size(), 1);
  EXPECT_EQ(message.notes(0), history.notes[0]);

  ASSERT_EQ(message.runs_size(), 1);
  const v1::HistoryRun& run = message.runs(0);
  EXPECT_EQ(run.run(), history.runs[0].run);
  EXPECT_EQ(run.test_time().seconds(), 1'767'600'000);
  EXPECT_EQ(run.test_time().nanos(), 123'456'000);
  EXPECT_EQ(run.duration_s(), 3600.0);
  ASSERT_EQ(run.analyses_size(), 1);
  const v1::HistoryAnalysis& analysis = run.analyses(0);
  EXPECT_EQ(analysis.analysis(), history.runs[0].analyses[0].analysis);
  EXPECT_EQ(analysis.create_time().seconds(), 1'767'603'600);
  EXPECT_EQ(analysis.create_time().nanos(), 1'000);
  EXPECT_EQ(analysis.verdict(), v1::AnalysisReport::OPERABLE);
  EXPECT_EQ(analysis.unit_hours(), 1234.5);
  EXPECT_TRUE(analysis.counted());
  EXPECT_EQ(analysis.identified_count(), 17);

  ASSERT_EQ(message.parameters_size(), 1);
  const v1::UnitParameterHistory& parameter = message.parameters(0);
  EXPECT_EQ(parameter.name(), "gyro_turn_on_bias.x");
  EXPECT_EQ(parameter.unit(), "rad/s");
  EXPECT_TRUE(parameter.turn_on_bias());
  ASSERT_EQ(parameter.points_size(), 1);
  const v1::RunParameterPoint& point = parameter.points(0);
  EXPECT_EQ(point.run(), run.run());
  EXPECT_EQ(point.analysis(), analysis.analysis());
  EXPECT_EQ(point.test_time().seconds(), run.test_time().seconds());
  EXPECT_EQ(point.test_time().nanos(), run.test_time().nanos());
  EXPECT_EQ(point.days(), 7.25);
  EXPECT_EQ(point.value(), 4.9e-7);
  EXPECT_EQ(point.std_error(), 2.0e-8);
  const v1::UnitParameterStatistics& statistics = parameter.statistics();
  EXPECT_EQ(statistics.count(), 6);
  EXPECT_EQ(statistics.mean(), 4.85e-7);
  EXPECT_EQ(statistics.run_to_run_sd(), 3.0e-8);
  EXPECT_EQ(statistics.run_to_run_sd_low(), 1.9e-8);
  EXPECT_EQ(statistics.run_to_run_sd_high(), 7.4e-8);
  EXPECT_EQ(statistics.rms_std_error(), 2.1e-8);
  EXPECT_EQ(statistics.turn_on_to_turn_on_sd(), 2.2e-8);
  const v1::UnitTrendFit& trend = statistics.trend();
  const kb::TrendFit fit = FittedTrend();
  EXPECT_TRUE(trend.fitted());
  EXPECT_TRUE(trend.weighted());
  EXPECT_EQ(trend.slope_per_day(), fit.slope_per_day);
  EXPECT_EQ(trend.slope_std_error_per_day(), fit.slope_std_error_per_day);
  EXPECT_EQ(trend.intercept(), fit.intercept);
  EXPECT_EQ(trend.p_value(), fit.p_value);
  EXPECT_EQ(trend.chi_square(), fit.chi_square);
  EXPECT_EQ(trend.degrees_of_freedom(), 4);
  EXPECT_EQ(trend.scatter_p_value(), fit.scatter_p_value);
  EXPECT_TRUE(trend.excess_scatter());
  EXPECT_EQ(trend.birge_ratio(), fit.birge_ratio);
}

TEST(HistoryCodec, EveryVerdictKeepsItsApiValueAndNoneIsUnspecified) {
  kb::UnitHistory history = FullHistory();
  kb::HistoryAnalysis& analysis = history.runs[0].analyses[0];
  analysis.verdict = engine::Verdict::kGood;
  EXPECT_EQ(ToProto(history).runs(0).analyses(0).verdict(), v1::AnalysisReport::GOOD);
  analysis.verdict = engine::Verdict::kFaulty;
  EXPECT_EQ(ToProto(history).runs(0).analyses(0).verdict(), v1::AnalysisReport::FAULTY);
  analysis.verdict.reset();
  EXPECT_EQ(ToProto(history).runs(0).analyses(0).verdict(), v1::AnalysisReport::VERDICT_UNSPECIFIED);
}

// A statistic the knowledge base did not give stays unset in the message:
// clients tell "no turn-on repeatability" and "no trend line" by presence.
TEST(HistoryCodec, AbsentStatisticsStayUnsetAndAnUnfittedTrendIsEmpty) {
  kb::ParameterStatistics statistics;
  statistics.count = 0;
  const v1::UnitParameterStatistics none = ToProto(statistics);
  EXPECT_FALSE(none.has_turn_on_to_turn_on_sd());
  EXPECT_FALSE(none.has_trend());

  statistics.count = 2;
  statistics.trend = kb::TrendFit();  // two points: no line
  const v1::UnitParameterStatistics unfitted = ToProto(statistics);
  ASSERT_TRUE(unfitted.has_trend());
  EXPECT_FALSE(unfitted.trend().fitted());
  EXPECT_EQ(unfitted.trend().ByteSizeLong(), 0u);

  statistics.turn_on_to_turn_on_sd = 0.0;  // every scatter explained by the SEs: a value, not "unknown"
  EXPECT_TRUE(ToProto(statistics).has_turn_on_to_turn_on_sd());
  EXPECT_EQ(ToProto(statistics).turn_on_to_turn_on_sd(), 0.0);

  kb::UnitHistory unknown_type;
  unknown_type.unit = "units/INS-H9";
  const v1::UnitHistory message = ToProto(unknown_type);
  EXPECT_TRUE(message.unit_type().empty());
  EXPECT_TRUE(message.next_page_token().empty());
  EXPECT_EQ(message.runs_size(), 0);
  EXPECT_EQ(message.parameters_size(), 0);
}

TEST(HistoryCodec, ARequestCarriesEveryFieldIntoTheQuery) {
  v1::GetUnitHistoryRequest request;
  request.set_unit("units/INS-H1");
  request.set_page_size(3);
  request.set_page_token("bmV4dA==");
  request.add_parameters("gyro_bias_gm.x.sigma");
  request.add_parameters("gyro_turn_on_bias.x");
  request.set_confidence(0.9);
  EXPECT_EQ(UnsetFields(request), std::vector<std::string>());
  const kb::UnitHistoryQuery query = UnitHistoryQueryOf(request);
  EXPECT_EQ(query.unit, "units/INS-H1");
  EXPECT_EQ(query.page_size, 3);
  EXPECT_EQ(query.page_token, "bmV4dA==");
  EXPECT_EQ(query.parameters, (std::vector<std::string>{"gyro_bias_gm.x.sigma", "gyro_turn_on_bias.x"}));
  EXPECT_EQ(query.confidence, 0.9);

  const kb::UnitHistoryQuery defaults = UnitHistoryQueryOf(v1::GetUnitHistoryRequest());
  EXPECT_EQ(defaults.page_size, 0);
  EXPECT_EQ(defaults.confidence, 0.0);  // the store's default
  EXPECT_TRUE(defaults.parameters.empty());
}

}  // namespace
}  // namespace insdiag::server
