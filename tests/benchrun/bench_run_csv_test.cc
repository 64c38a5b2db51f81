#include "insdiag/benchrun/bench_run_csv.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <string>
#include <tuple>

#include "test_runs.h"

namespace insdiag::benchrun {
namespace {

using testing::CsvText;
using ::testing::HasSubstr;
using testing::IsRefusalAt;
using testing::MessageOf;
using ::testing::Not;
using testing::ExpectSameRun;

constexpr double kRadiansPerDegree = std::numbers::pi / 180.0;
constexpr char kSource[] = "run.csv";

// Columns of CsvText rows (see test_runs.h).
constexpr int kColumnT = 1;
constexpr int kColumnGyroX = 6;
constexpr int kColumnGyroZ = 23;
constexpr int kColumnAccX = 32;
constexpr int kColumnAccY = 39;
constexpr int kColumnAccZ = 47;
constexpr int kColumnTemp = 61;
constexpr std::size_t kFieldAccX = 4;
constexpr std::size_t kFieldAccY = 5;
constexpr std::size_t kFieldAccZ = 6;

absl::Status ParseStatus(const std::string& text) { return ParseBenchRun(text, kSource).status(); }

InputLocation At(int line, int column, std::string field) {
  return {.source = kSource, .line = line, .column = column, .field = std::move(field)};
}

// ---------------------------------------------------------------------------
// Accepted input

TEST(ParseBenchRun, ReadsMetadataColumnsAndSamples) {
  const absl::StatusOr<engine::BenchRun> run = ParseBenchRun(CsvText().Text(), kSource);
  ASSERT_TRUE(run.ok()) << run.status();
  ExpectSameRun(*run, testing::StaticRun());
  EXPECT_NEAR(run->metadata.site.latitude_rad, 0.9698306, 1e-7);
  EXPECT_EQ(run->metadata.datasheet, engine::Datasheet{});
  EXPECT_TRUE(run->metadata.extra.empty());
}

TEST(ParseBenchRun, DatasheetKeysFillTheDatasheet) {
  CsvText csv;
  csv.metadata.insert(csv.metadata.end(),
                      {"# gyro_arw: 2.9e-06", "# gyro_bias_sigma: 4.8e-08", "# gyro_bias_tau: 3600",
                       "# acc_vrw: 1.5e-05", "# acc_bias_sigma: 0.0002", "# acc_bias_tau: 1800"});
  const absl::StatusOr<engine::BenchRun> run = ParseBenchRun(csv.Text(), kSource);
  ASSERT_TRUE(run.ok()) << run.status();
  const engine::Datasheet expected{.gyro_arw_rad_rts = 2.9e-06,
                                   .gyro_bias_sigma_rad_s = 4.8e-08,
                                   .gyro_bias_tau_s = 3600,
                                   .acc_vrw_mps_rts = 1.5e-05,
                                   .acc_bias_sigma_mps2 = 0.0002,
                                   .acc_bias_tau_s = 1800};
  EXPECT_EQ(run->metadata.datasheet, expected);
  EXPECT_TRUE(run->metadata.extra.empty());
}

TEST(ParseBenchRun, KeepsUnknownAndFreeMetadataInFileOrder) {
  CsvText csv;
  csv.metadata.insert(csv.metadata.begin() + 2, {"# operator: kim", "# table_firmware: 4.2.1",
                                                 "# started_at: 2024-03-01T09:15:00Z"});
  csv.metadata.insert(csv.metadata.end(),
                      {"# bench:  table 3  ", "# notes: warm-up: 20 min, door closed"});
  const absl::StatusOr<engine::BenchRun> run = ParseBenchRun(csv.Text(), kSource);
  ASSERT_TRUE(run.ok()) << run.status();
  const std::vector<std::pair<std::string, std::string>> expected = {
      {"operator", "kim"},
      {"table_firmware", "4.2.1"},
      {"started_at", "2024-03-01T09:15:00Z"},
      {"bench", "table 3"},
      {"notes", "warm-up: 20 min, door closed"}};
  EXPECT_EQ(run->metadata.extra, expected);
  EXPECT_EQ(run->metadata.unit_type, "INS-2000");
}

// The encoders' attitude is read where the file says so; without the key,
// where the reference attitude moves (only a table's encoders give that), and
// not where it stays constant (it may be an alignment's estimate).
TEST(ParseBenchRun, TheReferenceAttitudeIsReadWhereTheFileSaysEncodersOrTheTableTurns) {
  CsvText turning;
  turning.SetField(150, 9, "0.25");
  for (const auto& [csv, read] : {std::pair{CsvText(), false}, std::pair{turning, true}}) {
    const absl::StatusOr<engine::BenchRun> unsaid = ParseBenchRun(csv.Text(), kSource);
    ASSERT_TRUE(unsaid.ok()) << unsaid.status();
    EXPECT_EQ(unsaid->ReferenceAttitudeIsRead(), read) << "without the key, turning " << read;
    for (const auto& [value, said] : {std::pair{"encoders", true}, std::pair{"none", false}}) {
      CsvText with_key = csv;
      with_key.metadata.push_back(std::string("# reference_attitude_readout: ") + value);
      const absl::StatusOr<engine::BenchRun> run = ParseBenchRun(with_key.Text(), kSource);
      ASSERT_TRUE(run.ok()) << run.status();
      EXPECT_EQ(run->ReferenceAttitudeIsRead(), said) << value << ", turning " << read;
    }
  }
}

TEST(ParseBenchRun, ToleratesCrlfLineEnds) {
  const absl::StatusOr<engine::BenchRun> run = ParseBenchRun(CsvText().Text("\r\n"), kSource);
  ASSERT_TRUE(run.ok()) << run.status();
  ExpectSameRun(*run, testing::StaticRun());
}

TEST(ParseBenchRun, CrlfErrorsNameTheSameLineAndColumn) {
  CsvText csv;
  csv.SetField(4, 3, "abc");
  EXPECT_TRUE(IsRefusalAt(ParseStatus(csv.Text("\r\n")), At(12, kColumnGyroZ, "gyro_z")));
}

TEST(ParseBenchRun, ToleratesByteOrderMarkBlankLinesAndSpaces) {
  CsvText csv;
  csv.metadata.insert(csv.metadata.begin() + 1, "");
  csv.header = " t , gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,ref_roll,ref_pitch,ref_yaw,temp ";
  csv.SetField(3, 1, " 1.1e-05 ");
  csv.SetField(5, 1, "+1.1e-05");
  const absl::StatusOr<engine::BenchRun> run =
      ParseBenchRun("\xEF\xBB\xBF" + csv.Text() + "\n \n\r\n", kSource);
  ASSERT_TRUE(run.ok()) << run.status();
  ExpectSameRun(*run, testing::StaticRun());
}

TEST(ParseBenchRun, AcceptsTheLastLineWithoutLineEnd) {
  std::string text = CsvText().Text();
  text.pop_back();
  const absl::StatusOr<engine::BenchRun> run = ParseBenchRun(text, kSource);
  ASSERT_TRUE(run.ok()) << run.status();
  EXPECT_EQ(run->samples.size(), 200u);
}

TEST(ParseBenchRun, ColumnsMayComeInAnyOrder) {
  const CsvText canonical;
  std::mt19937 rng(20240301);
  for (int trial = 0; trial < 5; ++trial) {
    std::vector<std::size_t> order(11);
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::shuffle(order.begin(), order.end(), rng);
    const auto permute = [&order](const std::string& line) {
      const std::vector<std::string> fields = CsvText::Split(line);
      std::vector<std::string> permuted;
      for (const std::size_t k : order) permuted.push_back(fields[k]);
      return CsvText::Join(permuted);
    };
    CsvText shuffled = canonical;
    shuffled.header = permute(canonical.header);
    std::transform(canonical.rows.begin(), canonical.rows.end(), shuffled.rows.begin(), permute);
    const absl::StatusOr<engine::BenchRun> run = ParseBenchRun(shuffled.Text(), kSource);
    ASSERT_TRUE(run.ok()) << shuffled.header << ": " << run.status();
    ExpectSameRun(*run, testing::StaticRun());
  }
}

TEST(ParseBenchRun, IgnoresColumnsTheSpecDoesNotName) {
  CsvText csv;
  csv.header += ",encoder_ticks";
  for (std::string& row : csv.rows) row += ",not-a-number";
  const absl::StatusOr<engine::BenchRun> run = ParseBenchRun(csv.Text(), kSource);
  ASSERT_TRUE(run.ok()) << run.status();
  ExpectSameRun(*run, testing::StaticRun());
}

TEST(ParseBenchRun, TemperatureColumnIsOptional) {
  CsvText csv;
  csv.header.erase(csv.header.rfind(','));
  for (std::string& row : csv.rows) row.erase(row.rfind(','));
  const absl::StatusOr<engine::BenchRun> run = ParseBenchRun(csv.Text(), kSource);
  ASSERT_TRUE(run.ok()) << run.status();
  EXPECT_FALSE(run->has_temperature);
}

TEST(ParseBenchRun, LatitudeOfExactlyNinetyDegreesIsAccepted) {
  for (const char* latitude : {"90", "-90"}) {
    CsvText csv;
    csv.metadata[3] = std::string("# site_latitude_deg: ") + latitude;
    for (std::size_t i = 0; i < csv.rows.size(); ++i) csv.SetField(i, kFieldAccZ, "-9.832");
    const absl::StatusOr<engine::BenchRun> run = ParseBenchRun(csv.Text(), kSource);
    ASSERT_TRUE(run.ok()) << latitude << ": " << run.status();
    EXPECT_EQ(std::abs(run->metadata.site.latitude_rad), std::numbers::pi / 2);
  }
}

// The real ring-laser-gyro record (data/real), as `insdiag import` writes it
// from the repository's PSINS log (tests/CMakeLists.txt).
TEST(ParseBenchRun, RealRingLaserGyroRecording) {
  const absl::StatusOr<engine::BenchRun> run = ReadBenchRunFile(INSDIAG_REAL_RECORD_CSV);
  ASSERT_TRUE(run.ok()) << run.status();
  EXPECT_EQ(run->samples.size(), 184718u);
  EXPECT_EQ(run->metadata.unit_serial, "PSINS-RLG-2014");
  EXPECT_EQ(run->metadata.unit_type, "RLG-IMU");
  EXPECT_NEAR(run->metadata.site.latitude_rad, 34.246048 * kRadiansPerDegree, 1e-12);
  EXPECT_NEAR(run->metadata.site.longitude_rad, 108.909664 * kRadiansPerDegree, 1e-12);
  EXPECT_EQ(run->metadata.site.height_m, 380.0);
  EXPECT_FALSE(run->has_temperature);
  EXPECT_EQ(run->metadata.Extra("bench"), "static (vehicle at rest)");
  EXPECT_EQ(run->samples.front().t_s, 0.01);
  // Two counts of 0.1″ over 10 ms, as the converted copy the project was given
  // prints it (shared/data/real/rlg-static-psins.csv, ten digits).
  EXPECT_NEAR(run->samples.front().gyro_rad_s.z(), -9.696273622e-05, 5e-15);
  EXPECT_NEAR(run->NominalIntervalS(), 0.01, 1e-9);
}

// ---------------------------------------------------------------------------
// Refusals: one test per rule, each naming line, column and field.

TEST(ParseBenchRunRefuses, ValueThatIsNotANumber) {
  CsvText csv;
  csv.SetField(4, 3, "abc");
  const absl::Status status = ParseStatus(csv.Text());
  EXPECT_TRUE(IsRefusalAt(status, At(12, kColumnGyroZ, "gyro_z")));
  EXPECT_EQ(MessageOf(status), "run.csv:12:23: gyro_z: 'abc' is not a number");
}

TEST(ParseBenchRunRefuses, ValueWithTrailingGarbageOrDecimalComma) {
  for (const char* value : {"0.0012x", "0.0012 5", "", "0x1p3", "1.2.3"}) {
    CsvText csv;
    csv.SetField(7, kFieldAccX, value);
    EXPECT_TRUE(IsRefusalAt(ParseStatus(csv.Text()), At(csv.RowLine(7), kColumnAccX, "acc_x")))
        << "'" << value << "'";
  }
}

TEST(ParseBenchRunRefuses, NanOrInfinityInARow) {
  for (const char* value : {"nan", "NaN", "-nan", "inf", "-Infinity"}) {
    CsvText csv;
    csv.SetField(30, kFieldAccY, value);
    const absl::Status status = ParseStatus(csv.Text());
    EXPECT_TRUE(IsRefusalAt(status, At(csv.RowLine(30), kColumnAccY, "acc_y"))) << value;
    EXPECT_THAT(MessageOf(status), HasSubstr("is not a finite number"));
  }
}

TEST(ParseBenchRunRefuses, NumberOutOfTheRangeOfADouble) {
  CsvText csv;
  csv.SetField(2, 10, "1e999");
  EXPECT_TRUE(IsRefusalAt(ParseStatus(csv.Text()), At(csv.RowLine(2), kColumnTemp, "temp")));
}

TEST(ParseBenchRunRefuses, MetadataNumberThatIsNotANumber) {
  CsvText csv;
  csv.metadata[5] = "# site_height_m: 12O.5";
  const absl::Status status = ParseStatus(csv.Text());
  EXPECT_TRUE(IsRefusalAt(status, At(6, 18, "site_height_m")));
  EXPECT_EQ(MessageOf(status), "run.csv:6:18: site_height_m: '12O.5' is not a number");
}

// The initial attitude's accuracy as the file states it: a level σ, and a
// heading σ or `unknown` where the bench did not survey it.
TEST(ParseBenchRun, ReadsTheInitialAttitudesStatedAccuracy) {
  const engine::StatedAttitudeAccuracy unsaid = ParseBenchRun(CsvText().Text(), kSource)->metadata.AttitudeAccuracy();
  EXPECT_FALSE(unsaid.level_sigma_rad.has_value());
  EXPECT_FALSE(unsaid.heading_sigma_rad.has_value());
  EXPECT_TRUE(unsaid.heading_surveyed);
  CsvText csv;
  csv.metadata.push_back("# reference_level_sigma_rad: 0.0012");
  csv.metadata.push_back("# reference_heading_sigma_rad: unknown");
  const absl::StatusOr<engine::BenchRun> run = ParseBenchRun(csv.Text(), kSource);
  ASSERT_TRUE(run.ok()) << run.status();
  const engine::StatedAttitudeAccuracy stated = run->metadata.AttitudeAccuracy();
  EXPECT_EQ(stated.level_sigma_rad, 0.0012);
  EXPECT_FALSE(stated.heading_surveyed);
  EXPECT_FALSE(stated.heading_sigma_rad.has_value());
  csv.metadata.back() = "# reference_heading_sigma_rad: 3e-4";
  EXPECT_EQ(ParseBenchRun(csv.Text(), kSource)->metadata.AttitudeAccuracy().heading_sigma_rad, 3e-4);
}

TEST(ParseBenchRunRefuses, AnInitialAttitudeAccuracyThatIsNoPositiveSigma) {
  for (const auto& [line_text, column, key, why] :
       {std::tuple{"# reference_level_sigma_rad: unknown", 30, "reference_level_sigma_rad",
                   "expected a positive 1σ in radians, got 'unknown'"},
        std::tuple{"# reference_heading_sigma_rad: -1e-3", 32, "reference_heading_sigma_rad",
                   "expected a positive 1σ in radians or 'unknown', got '-1e-3'"}}) {
    CsvText csv;
    csv.metadata.push_back(line_text);
    const absl::Status status = ParseStatus(csv.Text());
    const int line = static_cast<int>(csv.metadata.size());
    EXPECT_TRUE(IsRefusalAt(status, At(line, column, key))) << status;
    EXPECT_THAT(MessageOf(status), HasSubstr(why));
  }
}

TEST(ParseBenchRunRefuses, AReferenceAttitudeReadoutThatIsNeitherEncodersNorNone) {
  CsvText csv;
  csv.metadata.push_back("# reference_attitude_readout: sometimes");
  const absl::Status status = ParseStatus(csv.Text());
  const int line = static_cast<int>(csv.metadata.size());
  EXPECT_TRUE(IsRefusalAt(status, At(line, 31, "reference_attitude_readout"))) << status;
  EXPECT_THAT(MessageOf(status), HasSubstr("expected 'encoders' or 'none', got 'sometimes'"));
}

// A lone carriage return inside a value is not a line break of the format,
// and would not survive being written back (found by the CSV fuzzer).
TEST(ParseBenchRunRefuses, AControlCharacterInsideAMetadataValue) {
  CsvText csv;
  csv.metadata[2] = "# unit_type: INS\r2000";
  const absl::Status status = ParseStatus(csv.Text());
  EXPECT_TRUE(IsRefusalAt(status, At(3, 17, "unit_type"))) << status;
  EXPECT_THAT(MessageOf(status), HasSubstr("control character U+000D"));
}

TEST(ParseBenchRunRefuses, MetadataNumberThatIsNanOrInfinite) {
  CsvText csv;
  csv.metadata.push_back("# gyro_arw: nan");
  csv.metadata.push_back("# acc_vrw: inf");
  EXPECT_TRUE(IsRefusalAt(ParseStatus(csv.Text()), At(7, 13, "gyro_arw")));
  csv.metadata.erase(csv.metadata.begin() + 6);
  EXPECT_TRUE(IsRefusalAt(ParseStatus(csv.Text()), At(7, 12, "acc_vrw")));
}

TEST(ParseBenchRunRefuses, SiteAngleThatIsNotANumber) {
  CsvText csv;
  csv.metadata[4] = "# site_longitude_deg: 38°09'";
  EXPECT_TRUE(IsRefusalAt(ParseStatus(csv.Text()), At(5, 23, "site_longitude_deg")));
}

TEST(ParseBenchRunRefuses, MissingRequiredKey) {
  for (const std::size_t dropped : {0, 1, 3, 4, 5}) {
    CsvText csv;
    const std::string line = csv.metadata[dropped];
    const std::string key = line.substr(2, line.find(':') - 2);
    csv.metadata.erase(csv.metadata.begin() + static_cast<std::ptrdiff_t>(dropped));
    const absl::Status status = ParseStatus(csv.Text());
    EXPECT_TRUE(IsRefusalAt(status, At(csv.HeaderLine(), 0, key))) << key;
    EXPECT_THAT(MessageOf(status), HasSubstr("missing required metadata key"));
  }
}

TEST(ParseBenchRunRefuses, EmptyUnitSerial) {
  CsvText csv;
  csv.metadata[1] = "# unit_serial:";
  EXPECT_TRUE(IsRefusalAt(ParseStatus(csv.Text()), At(2, 15, "unit_serial")));
}

TEST(ParseBenchRunRefuses, MissingColumn) {
  CsvText csv;
  csv.header = "t,gyro_x,gyro_z,acc_x,acc_y,acc_z,ref_roll,ref_pitch,ref_yaw,temp";
  const absl::Status status = ParseStatus(csv.Text());
  EXPECT_TRUE(IsRefusalAt(status, At(7, 0, "gyro_y")));
  EXPECT_EQ(MessageOf(status), "run.csv:7: gyro_y: missing required column");
}

TEST(ParseBenchRunRefuses, DuplicateColumn) {
  CsvText csv;
  csv.header = "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,ref_roll,ref_pitch,ref_yaw,gyro_x";
  const absl::Status status = ParseStatus(csv.Text());
  EXPECT_TRUE(IsRefusalAt(status, At(7, 69, "gyro_x")));
  EXPECT_THAT(MessageOf(status), HasSubstr("duplicate column"));
}

TEST(ParseBenchRunRefuses, UnknownFormat) {
  for (const char* format :
       {"insdiag-bench-run/3", "insdiag-bench-run/1.0", "INSDIAG-BENCH-RUN/1"}) {
    CsvText csv;
    csv.metadata[0] = std::string("# format: ") + format;
    const absl::Status status = ParseStatus(csv.Text());
    EXPECT_TRUE(IsRefusalAt(status, At(1, 11, "format"))) << format;
    EXPECT_THAT(MessageOf(status), HasSubstr("unknown format"));
  }
}

TEST(ParseBenchRunRefuses, UnknownFormatBeforeLaterErrors) {
  CsvText csv;
  csv.metadata[0] = "# format: insdiag-bench-run/3";
  csv.metadata.push_back("# this line is not metadata of version 1");
  EXPECT_TRUE(IsRefusalAt(ParseStatus(csv.Text()), At(1, 11, "format")));
}

TEST(ParseBenchRunRefuses, DuplicateMetadataKey) {
  CsvText csv;
  csv.metadata.insert(csv.metadata.begin() + 2, "# bench: table 3");
  csv.metadata.push_back("#  bench: table 4");
  const absl::Status status = ParseStatus(csv.Text());
  EXPECT_TRUE(IsRefusalAt(status, At(8, 4, "bench")));
  EXPECT_THAT(MessageOf(status), HasSubstr("first at line 3"));
}

TEST(ParseBenchRunRefuses, DuplicateSpecMetadataKey) {
  CsvText csv;
  csv.metadata.push_back("# site_height_m: 126.0");
  EXPECT_TRUE(IsRefusalAt(ParseStatus(csv.Text()), At(7, 3, "site_height_m")));
}

TEST(ParseBenchRunRefuses, MetadataLineThatIsNotKeyColonValue) {
  const std::vector<std::pair<std::string, int>> cases = {
      {"# just a comment", 3},   // no colon
      {"#", 2},                  // nothing at all
      {"# Unit Serial: 42", 3},  // not a lower-case key
      {"# site-height: 3", 3},   // '-' in key
      {"# : value", 3},          // empty key
      {"#\t2nd_key: value", 3},  // key starting with a digit
  };
  for (const auto& [line, column] : cases) {
    CsvText csv;
    csv.metadata.insert(csv.metadata.begin() + 3, line);
    EXPECT_TRUE(IsRefusalAt(ParseStatus(csv.Text()), At(4, column, "metadata"))) << line;
  }
}

TEST(ParseBenchRunRefuses, NonIncreasingTime) {
  for (const char* t : {"0.50", "0.49"}) {  // row 49 has t = 0.50
    CsvText csv;
    csv.SetField(50, 0, t);
    const absl::Status status = ParseStatus(csv.Text());
    EXPECT_TRUE(IsRefusalAt(status, At(csv.RowLine(50), kColumnT, "t"))) << t;
    EXPECT_THAT(MessageOf(status), HasSubstr("does not increase"));
  }
}

TEST(ParseBenchRunRefuses, GapLongerThanFiveNominalIntervals) {
  CsvText csv;
  // Rows 120..124 removed: t jumps from 1.20 to 1.26, six intervals.
  csv.rows.erase(csv.rows.begin() + 120, csv.rows.begin() + 125);
  const absl::Status status = ParseStatus(csv.Text());
  EXPECT_TRUE(IsRefusalAt(status, At(csv.RowLine(120), kColumnT, "t")));
  EXPECT_THAT(MessageOf(status), HasSubstr("nominal intervals"));
}

TEST(ParseBenchRunRefuses, OnlyTheFirstGapIsReported) {
  CsvText csv;
  csv.rows.erase(csv.rows.begin() + 150, csv.rows.begin() + 170);  // a longer gap later
  csv.rows.erase(csv.rows.begin() + 120, csv.rows.begin() + 127);
  EXPECT_TRUE(IsRefusalAt(ParseStatus(csv.Text()), At(csv.RowLine(120), kColumnT, "t")));
}

TEST(ParseBenchRunAccepts, GapOfFourIntervals) {
  CsvText csv;
  csv.rows.erase(csv.rows.begin() + 120, csv.rows.begin() + 123);
  EXPECT_TRUE(ParseStatus(csv.Text()).ok());
}

TEST(ParseBenchRunRefuses, RowWithTooFewFields) {
  CsvText csv;
  csv.rows[9].erase(csv.rows[9].rfind(','));
  const absl::Status status = ParseStatus(csv.Text());
  const int end_column = static_cast<int>(csv.rows[9].size()) + 1;
  EXPECT_TRUE(IsRefusalAt(status, At(csv.RowLine(9), end_column, "temp")));
  EXPECT_THAT(MessageOf(status), HasSubstr("row has 10 fields, expected 11"));
}

TEST(ParseBenchRunRefuses, RowWithTooManyFields) {
  CsvText csv;
  const int extra_column = static_cast<int>(csv.rows[9].size()) + 2;
  csv.rows[9] += ",1,2";
  const absl::Status status = ParseStatus(csv.Text());
  EXPECT_TRUE(IsRefusalAt(status, At(csv.RowLine(9), extra_column, "row")));
  EXPECT_THAT(MessageOf(status), HasSubstr("row has 13 fields, expected 11"));
}

TEST(ParseBenchRunRefuses, EmptyRowBetweenRows) {
  CsvText csv;
  csv.rows.insert(csv.rows.begin() + 9, "");
  EXPECT_TRUE(IsRefusalAt(ParseStatus(csv.Text()), At(csv.RowLine(9), 1, "row")));
}

TEST(ParseBenchRunRefuses, GyroRateInDegreesPerSecond) {
  CsvText csv;
  csv.SetField(20, 1, "-57.3");
  const absl::Status status = ParseStatus(csv.Text());
  EXPECT_TRUE(IsRefusalAt(status, At(csv.RowLine(20), kColumnGyroX, "gyro_x")));
  EXPECT_THAT(MessageOf(status), HasSubstr("beyond ±35 rad/s: looks like deg/s"));
}

TEST(ParseBenchRunRefuses, GyroRateBeyondEvenDegreesPerSecond) {
  CsvText csv;
  csv.SetField(20, 3, "4000");
  const absl::Status status = ParseStatus(csv.Text());
  EXPECT_TRUE(IsRefusalAt(status, At(csv.RowLine(20), kColumnGyroZ, "gyro_z")));
  EXPECT_THAT(MessageOf(status), Not(HasSubstr("deg/s")));
}

TEST(ParseBenchRunRefuses, SpecificForceBeyondLimit) {
  CsvText csv;
  csv.SetField(150, kFieldAccY, "500.5");
  const absl::Status status = ParseStatus(csv.Text());
  EXPECT_TRUE(IsRefusalAt(status, At(csv.RowLine(150), kColumnAccY, "acc_y")));
  EXPECT_THAT(MessageOf(status), HasSubstr("beyond ±500 m/s²"));
}

TEST(ParseBenchRunRefuses, LatitudeOutsideNinetyDegrees) {
  CsvText csv;
  csv.metadata[3] = "# site_latitude_deg: 95.5";
  const absl::Status status = ParseStatus(csv.Text());
  EXPECT_TRUE(IsRefusalAt(status, At(4, 22, "site_latitude_deg")));
  EXPECT_THAT(MessageOf(status), HasSubstr("outside ±90°"));
}

TEST(ParseBenchRunRefuses, SpecificForceInUnitsOfG) {
  CsvText csv;
  for (std::size_t i = 0; i < csv.rows.size(); ++i) csv.SetField(i, kFieldAccZ, "-1.0009");
  const absl::Status status = ParseStatus(csv.Text());
  EXPECT_TRUE(IsRefusalAt(status, At(csv.RowLine(0), kColumnAccX, "acc_x")));
  EXPECT_THAT(MessageOf(status), HasSubstr("looks like units of g, expected m/s²"));
}

TEST(ParseBenchRunRefuses, SpecificForceFarFromGravity) {
  CsvText csv;
  // Only the first second counts: later rows at -9.8154 do not rescue it.
  for (std::size_t i = 0; i < 100; ++i) csv.SetField(i, kFieldAccZ, "-8.7");
  const absl::Status status = ParseStatus(csv.Text());
  EXPECT_TRUE(IsRefusalAt(status, At(csv.RowLine(0), kColumnAccX, "acc_x")));
  EXPECT_THAT(MessageOf(status), HasSubstr("local normal gravity is 9.81"));
  EXPECT_THAT(MessageOf(status), Not(HasSubstr("units of g")));
}

TEST(ParseBenchRunAccepts, SpecificForceWithinTenPercentOfGravity) {
  CsvText csv;
  for (std::size_t i = 0; i < 100; ++i) csv.SetField(i, kFieldAccZ, "-8.9");
  EXPECT_TRUE(ParseStatus(csv.Text()).ok());
}

TEST(ParseBenchRunRefuses, RunShorterThanASecondFarFromGravity) {
  CsvText csv(20);
  for (std::size_t i = 0; i < csv.rows.size(); ++i) csv.SetField(i, kFieldAccZ, "-0.98");
  const absl::Status status = ParseStatus(csv.Text());
  EXPECT_TRUE(IsRefusalAt(status, At(csv.RowLine(0), kColumnAccX, "acc_x")));
  EXPECT_THAT(MessageOf(status), HasSubstr("(20 samples)"));
}

TEST(ParseBenchRunRefuses, RunWithNoSamples) {
  CsvText csv(0);
  const absl::Status status = ParseStatus(csv.Text() + "\n\n");
  EXPECT_TRUE(IsRefusalAt(status, At(8, 0, "samples")));
  EXPECT_THAT(MessageOf(status), HasSubstr("no samples"));
}

TEST(ParseBenchRunRefuses, TextWithoutHeader) {
  CsvText csv;
  std::string text;
  for (const std::string& line : csv.metadata) text += line + "\n";
  EXPECT_TRUE(IsRefusalAt(ParseStatus(text), At(7, 0, "header")));
  EXPECT_TRUE(IsRefusalAt(ParseStatus(""), At(1, 0, "format")));
}

TEST(ParseBenchRunRefuses, TheFirstErrorInLineOrder) {
  CsvText csv;
  csv.SetField(40, 2, "x");
  csv.SetField(60, 2, "99");
  csv.SetField(30, 3, "y");
  EXPECT_TRUE(IsRefusalAt(ParseStatus(csv.Text()), At(csv.RowLine(30), kColumnGyroZ, "gyro_z")));
}

TEST(ParseBenchRunRefuses, ColumnsCountCharactersNotBytes) {
  CsvText csv;
  csv.header =
      "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,ref_roll,ref_pitch,ref_yaw,température,temp";
  for (std::size_t i = 0; i < csv.rows.size(); ++i) {
    csv.rows[i].insert(csv.rows[i].rfind(',') + 1, "°C,");
  }
  csv.SetField(3, 11, "warm");
  // "°C," is 3 characters (4 bytes) inserted before temp.
  EXPECT_TRUE(IsRefusalAt(ParseStatus(csv.Text()), At(csv.RowLine(3), kColumnTemp + 3, "temp")));
}

TEST(ReadBenchRunFile, NamesTheMissingFile) {
  const absl::StatusOr<engine::BenchRun> run = ReadBenchRunFile("/nonexistent/run.csv");
  EXPECT_EQ(run.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(MessageOf(run.status()), HasSubstr("/nonexistent/run.csv"));
}

TEST(ReadBenchRunFile, ErrorsNameThePath) {
  const std::filesystem::path path =
      std::filesystem::path(::testing::TempDir()) / "benchrun_error_names_path.csv";
  CsvText csv;
  csv.SetField(4, 3, "abc");
  std::ofstream(path) << csv.Text();
  const absl::StatusOr<engine::BenchRun> run = ReadBenchRunFile(path);
  EXPECT_TRUE(IsRefusalAt(run.status(),
                          {.source = path.string(), .line = 12, .column = 23, .field = "gyro_z"}));
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace insdiag::benchrun

namespace insdiag::benchrun {
namespace {

// Format 2 (docs/MULTI_POSITION.md): a multi-position test's segment starts
// in `segment_starts`; they survive writing and reading, and a file that
// cannot hold them is refused at the key's line.
TEST(ParseBenchRunSegments, Format2CarriesSegmentStartsThroughWritingAndReading) {
  engine::BenchRun run = testing::StaticRun();
  run.metadata.format = std::string(kFormatV2);
  run.metadata.segment_starts = {50, 120};
  const std::string text = FormatBenchRun(run);
  EXPECT_NE(text.find("# format: insdiag-bench-run/2\n"), std::string::npos);
  EXPECT_NE(text.find("# segment_starts: 50,120\n"), std::string::npos);
  auto read = ParseBenchRun(text, "test.csv");
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(read->metadata.segment_starts, (std::vector<std::size_t>{50, 120}));
  EXPECT_TRUE(read->metadata.extra.empty());
  EXPECT_TRUE(read->StartsSegment(120));
  EXPECT_FALSE(read->StartsSegment(119));
  // A run of one segment is still written as version 1.
  EXPECT_EQ(FormatBenchRun(testing::StaticRun()).rfind("# format: insdiag-bench-run/1\n", 0), 0u);
}

TEST(ParseBenchRunSegments, RefusesSegmentsOutsideFormat2OrOutsideTheRun) {
  testing::CsvText v1;
  v1.metadata.push_back("# segment_starts: 50");
  auto refused = ParseBenchRun(v1.Text(), "v1.csv");
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.status().message(), "v1.csv:7:3: segment_starts: segments need format 'insdiag-bench-run/2'");

  testing::CsvText v2;
  v2.metadata[0] = "# format: insdiag-bench-run/2";
  v2.metadata.push_back("# segment_starts: 50,40");
  refused = ParseBenchRun(v2.Text(), "v2.csv");
  ASSERT_FALSE(refused.ok());
  EXPECT_THAT(std::string(refused.status().message()), ::testing::HasSubstr("v2.csv:7:3: segment_starts: 40 is not after 50"));

  v2.metadata.back() = "# segment_starts: 500";
  refused = ParseBenchRun(v2.Text(), "v2.csv");
  ASSERT_FALSE(refused.ok());
  EXPECT_THAT(std::string(refused.status().message()), ::testing::HasSubstr("segment start 500 is past the last sample"));

  v2.metadata.back() = "# segment_starts: 5x";
  refused = ParseBenchRun(v2.Text(), "v2.csv");
  ASSERT_FALSE(refused.ok());
  EXPECT_THAT(std::string(refused.status().message()), ::testing::HasSubstr("'5x' is not a sample index"));
}

}  // namespace
}  // namespace insdiag::benchrun
