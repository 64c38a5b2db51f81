// A bench-run text read line by line as it is written (BenchRunLineStream):
// the same samples and the same refusals, at the same places, as reading the
// whole text at once.
#include <gtest/gtest.h>

#include "insdiag/benchrun/bench_run_csv.h"
#include "test_runs.h"

namespace insdiag::benchrun {
namespace {

using testing::CsvText;

// Feeds the text's lines one by one; the first refusal, else Finish's.
absl::Status StreamLines(const std::string& text, BenchRunLineStream& stream, std::vector<engine::ImuSample>& samples) {
  size_t begin = 0;
  while (begin < text.size()) {
    const size_t end = std::min(text.find('\n', begin), text.size());
    if (auto status = stream.AddLine(std::string_view(text).substr(begin, end - begin)); !status.ok()) return status;
    for (const auto& s : stream.TakeSamples()) samples.push_back(s);
    begin = end + 1;
  }
  return stream.Finish();
}

TEST(BenchRunLineStream, ReadsTheSamplesReadingTheWholeTextReads) {
  const CsvText csv(300);
  for (const std::string_view line_end : {"\n", "\r\n"}) {
    const std::string text = csv.Text(line_end);
    auto whole = ParseBenchRun(text, "run.csv");
    ASSERT_TRUE(whole.ok()) << whole.status();
    BenchRunLineStream stream("run.csv");
    std::vector<engine::ImuSample> samples;
    ASSERT_TRUE(StreamLines(text, stream, samples).ok());
    ASSERT_TRUE(stream.started());
    EXPECT_EQ(stream.run().metadata.unit_serial, whole->metadata.unit_serial);
    EXPECT_EQ(stream.run().metadata.site.latitude_rad, whole->metadata.site.latitude_rad);
    EXPECT_EQ(stream.run().has_temperature, whole->has_temperature);
    ASSERT_EQ(samples.size(), whole->samples.size());
    for (size_t i = 0; i < samples.size(); ++i) {
      EXPECT_EQ(samples[i].t_s, whole->samples[i].t_s);
      EXPECT_EQ(samples[i].acc_mps2, whole->samples[i].acc_mps2);
      EXPECT_EQ(samples[i].temp_degc, whole->samples[i].temp_degc);
    }
  }
}

TEST(BenchRunLineStream, RefusesABadRowAtTheLineAndColumnTheWholeReadNames) {
  CsvText bad_number(300);
  bad_number.SetField(250, 3, "abc");  // gyro_z
  CsvText time_backwards(300);
  time_backwards.SetField(120, 0, "1.00");  // t goes back
  for (const CsvText* csv : {&bad_number, &time_backwards}) {
    const std::string text = csv->Text();
    const absl::Status whole = ParseBenchRun(text, "run.csv").status();
    ASSERT_FALSE(whole.ok());
    BenchRunLineStream stream("run.csv");
    std::vector<engine::ImuSample> samples;
    const absl::Status streamed = StreamLines(text, stream, samples);
    const auto where = LocationOf(whole);
    ASSERT_TRUE(where.has_value()) << whole;
    EXPECT_TRUE(testing::IsRefusalAt(streamed, *where)) << "whole text: " << whole;
  }
}

TEST(BenchRunLineStream, RefusesAMissingKeyAndATextWithoutHeader) {
  CsvText no_serial(10);
  no_serial.metadata.erase(no_serial.metadata.begin() + 1);
  std::vector<engine::ImuSample> samples;
  BenchRunLineStream stream("run.csv");
  const absl::Status streamed = StreamLines(no_serial.Text(), stream, samples);
  EXPECT_EQ(streamed, ParseBenchRun(no_serial.Text(), "run.csv").status());

  BenchRunLineStream headless("run.csv");
  ASSERT_TRUE(headless.AddLine("# format: insdiag-bench-run/1").ok());
  const absl::Status ended = headless.Finish();
  EXPECT_EQ(ended.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_FALSE(headless.started());
}

}  // namespace
}  // namespace insdiag::benchrun
