#include "insdiag/benchrun/bench_run_validation.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <string>

#include "insdiag/benchrun/bench_run_csv.h"
#include "test_runs.h"

namespace insdiag::benchrun {
namespace {

using testing::CsvText;
using ::testing::HasSubstr;
using testing::IsRefusalAt;
using testing::MessageOf;
using testing::StaticRun;

constexpr char kSource[] = "upload";
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

InputLocation Field(std::string path) { return {.source = kSource, .field = std::move(path)}; }

absl::Status Validate(const engine::BenchRun& run) { return ValidateBenchRun(run, kSource); }

// The part of a refusal's message after "location: field: ".
std::string DetailOf(const absl::Status& status) {
  const std::string message = MessageOf(status);
  const std::string field = LocationOf(status).value().field;
  return message.substr(message.find(": " + field + ": ") + field.size() + 4);
}

TEST(ValidateBenchRun, AcceptsAValidRun) { EXPECT_TRUE(Validate(StaticRun()).ok()); }

TEST(ValidateBenchRun, RefusesANonFiniteValue) {
  engine::BenchRun run = StaticRun();
  run.samples[12].gyro_rad_s.x() = kNan;
  const absl::Status status = Validate(run);
  EXPECT_TRUE(IsRefusalAt(status, Field("samples[12].gyro_x")));
  EXPECT_EQ(MessageOf(status), "upload: samples[12].gyro_x: nan is not a finite number");
}

TEST(ValidateBenchRun, TemperatureCountsOnlyWhenTheRunHasIt) {
  engine::BenchRun run = StaticRun();
  run.samples[3].temp_degc = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(IsRefusalAt(Validate(run), Field("samples[3].temp")));
  run.has_temperature = false;
  EXPECT_TRUE(Validate(run).ok());
}

TEST(ValidateBenchRun, RefusesNonIncreasingTime) {
  engine::BenchRun run = StaticRun();
  run.samples[50].t_s = run.samples[49].t_s;
  EXPECT_TRUE(IsRefusalAt(Validate(run), Field("samples[50].t")));
}

TEST(ValidateBenchRun, RefusesAGapWhereItEnds) {
  engine::BenchRun run = StaticRun();
  for (std::size_t i = 120; i < run.samples.size(); ++i) run.samples[i].t_s += 0.06;
  EXPECT_TRUE(IsRefusalAt(Validate(run), Field("samples[120].t")));
}

TEST(ValidateBenchRun, NominalIntervalIsTheMedianNotTheMean) {
  // A third of the intervals doubled: the median stays 10 ms, so a 60 ms gap
  // is refused though it is under 5 mean intervals (67 ms).
  engine::BenchRun run = StaticRun();
  double t = 0.0;
  for (std::size_t i = 0; i < run.samples.size(); ++i) {
    t += (i % 3 == 0) ? 0.02 : 0.01;
    run.samples[i].t_s = t;
  }
  EXPECT_TRUE(Validate(run).ok());
  for (std::size_t i = 150; i < run.samples.size(); ++i) run.samples[i].t_s += 0.04;
  EXPECT_TRUE(IsRefusalAt(Validate(run), Field("samples[150].t")));
}

TEST(ValidateBenchRun, RefusesGyroRatesInDegreesPerSecond) {
  engine::BenchRun run = StaticRun();
  run.samples[12].gyro_rad_s.z() = 90.0;
  const absl::Status status = Validate(run);
  EXPECT_TRUE(IsRefusalAt(status, Field("samples[12].gyro_z")));
  EXPECT_EQ(DetailOf(status), "90 rad/s is beyond ±35 rad/s: looks like deg/s, expected rad/s");
}

TEST(ValidateBenchRun, RefusesSpecificForceBeyondTheLimit) {
  engine::BenchRun run = StaticRun();
  run.samples[150].acc_mps2.x() = -981.0;
  EXPECT_TRUE(IsRefusalAt(Validate(run), Field("samples[150].acc_x")));
}

TEST(ValidateBenchRun, RefusesSpecificForceInUnitsOfG) {
  engine::BenchRun run = StaticRun();
  for (engine::ImuSample& sample : run.samples) sample.acc_mps2 /= 9.80665;
  const absl::Status status = Validate(run);
  EXPECT_TRUE(IsRefusalAt(status, Field("samples[0].acc_x")));
  EXPECT_THAT(MessageOf(status), HasSubstr("looks like units of g, expected m/s²"));
}

TEST(ValidateBenchRun, GravityUsesTheSiteLatitudeAndHeight) {
  // 8.84 m/s² is 9.6 % below equatorial gravity (9.7803) and 10.1 % below
  // polar gravity (9.8322): the same data pass at the equator only.
  engine::BenchRun run = StaticRun();
  for (engine::ImuSample& sample : run.samples) sample.acc_mps2 = {0.0, 0.0, -8.84};
  run.metadata.site.latitude_rad = 0.0;  // γ = 9.7803: 8.84 is 9.6 % low
  run.metadata.site.height_m = 0.0;
  EXPECT_TRUE(Validate(run).ok());
  run.metadata.site.latitude_rad = std::numbers::pi / 2;  // γ = 9.8322: 10.1 % low
  EXPECT_TRUE(IsRefusalAt(Validate(run), Field("samples[0].acc_x")));
}

TEST(ValidateBenchRun, RefusesLatitudeOutsideNinetyDegrees) {
  engine::BenchRun run = StaticRun();
  run.metadata.site.latitude_rad = -1.6;
  const absl::Status status = Validate(run);
  EXPECT_TRUE(IsRefusalAt(status, Field("metadata.site.latitude_rad")));
  EXPECT_THAT(MessageOf(status), HasSubstr("latitude -91.67324722"));
}

TEST(ValidateBenchRun, RefusesMissingOrUnknownFormat) {
  engine::BenchRun run = StaticRun();
  run.metadata.format = "";
  EXPECT_TRUE(IsRefusalAt(Validate(run), Field("metadata.format")));
  run.metadata.format = "insdiag-bench-run/3";
  EXPECT_TRUE(IsRefusalAt(Validate(run), Field("metadata.format")));
}

TEST(ValidateBenchRun, RefusesAMissingUnitSerial) {
  engine::BenchRun run = StaticRun();
  run.metadata.unit_serial.clear();
  EXPECT_TRUE(IsRefusalAt(Validate(run), Field("metadata.unit_serial")));
}

TEST(ValidateBenchRun, RefusesNonFiniteMetadataNumbers) {
  engine::BenchRun run = StaticRun();
  run.metadata.datasheet.acc_bias_tau_s = kNan;
  EXPECT_TRUE(IsRefusalAt(Validate(run), Field("metadata.datasheet.acc_bias_tau_s")));
  run.metadata.site.height_m = -std::numeric_limits<double>::infinity();
  EXPECT_TRUE(IsRefusalAt(Validate(run), Field("metadata.site.height_m")));
}

TEST(ValidateBenchRun, RefusesFreeMetadataTheTextFormatCannotCarry) {
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"Operator", "kim"}, {"site_height_m", "3"}, {"notes", "two\nlines"}, {"", "x"}};
  for (const auto& entry : bad) {
    engine::BenchRun run = StaticRun();
    run.metadata.extra = {{"bench", "table 3"}, entry};
    EXPECT_TRUE(IsRefusalAt(Validate(run), Field("metadata.extra[1]"))) << entry.first;
  }
  engine::BenchRun run = StaticRun();
  run.metadata.extra = {{"bench", "table 3"}, {"bench", "table 4"}};
  EXPECT_TRUE(IsRefusalAt(Validate(run), Field("metadata.extra[1]")));
}

TEST(ValidateBenchRun, RefusesARunWithNoSamples) {
  EXPECT_TRUE(IsRefusalAt(Validate(StaticRun(0)), Field("samples")));
}

TEST(ValidateBenchRun, AcceptsASingleSample) { EXPECT_TRUE(Validate(StaticRun(1)).ok()); }

// ---------------------------------------------------------------------------
// One rule set for both paths

TEST(BenchRunValidator, ChunkByChunkAgreesWithTheWholeRun) {
  std::mt19937 rng(424242);
  const std::vector<std::function<void(engine::BenchRun&)>> breakages = {
      [](engine::BenchRun&) {},
      [](engine::BenchRun& run) { run.samples[77].acc_mps2.y() = 600.0; },
      [](engine::BenchRun& run) { run.samples[150].t_s = 0.2; },
      [](engine::BenchRun& run) {
        for (std::size_t i = 180; i < run.samples.size(); ++i) run.samples[i].t_s += 1.0;
      },
  };
  for (const auto& breakage : breakages) {
    engine::BenchRun run = StaticRun();
    breakage(run);
    const absl::Status whole = Validate(run);
    for (int trial = 0; trial < 10; ++trial) {
      const FieldPathLocator locator{kSource};
      absl::StatusOr<BenchRunValidator> validator =
          BenchRunValidator::Create(run.metadata, run.has_temperature, locator);
      ASSERT_TRUE(validator.ok());
      absl::Status chunked;
      std::size_t begin = 0;
      while (chunked.ok() && begin < run.samples.size()) {
        const std::size_t size = std::uniform_int_distribution<std::size_t>(1, 40)(rng);
        const std::span<const engine::ImuSample> chunk =
            std::span(run.samples).subspan(begin, std::min(size, run.samples.size() - begin));
        chunked = validator->Add(chunk);
        begin += chunk.size();
      }
      if (chunked.ok()) chunked = validator->Finish();
      EXPECT_EQ(chunked, whole);
    }
  }
}

// The CSV reader and ValidateBenchRun apply the same rule code: the same
// broken sample is refused with the same words, the reader naming the line
// and column, the typed path the field path.
TEST(BenchRunValidator, CsvAndTypedPathsRefuseAlike) {
  struct Case {
    std::size_t row;
    std::size_t column;  // in CsvText rows
    std::string text;
    double value;
    std::string path;
  };
  const std::vector<Case> cases = {
      {12, 2, "40", 40.0, "samples[12].gyro_y"},
      {12, 5, "-777", -777.0, "samples[12].acc_y"},
      {60, 0, "0.3", 0.3, "samples[60].t"},
      {0, 6, "-1", -1.0, "samples[0].acc_x"},  // whole first second in g (set below)
  };
  for (const Case& c : cases) {
    CsvText csv;
    engine::BenchRun run = StaticRun();
    if (c.path == "samples[0].acc_x") {
      for (std::size_t i = 0; i < csv.rows.size(); ++i) {
        csv.SetField(i, c.column, c.text);
        run.samples[i].acc_mps2.z() = c.value;
      }
    } else {
      csv.SetField(c.row, c.column, c.text);
      double& value = c.column == 0 ? run.samples[c.row].t_s
                                    : (c.column < 4 ? run.samples[c.row].gyro_rad_s[c.column - 1]
                                                    : run.samples[c.row].acc_mps2[c.column - 4]);
      value = c.value;
    }
    const absl::Status typed = Validate(run);
    const absl::Status parsed = ParseBenchRun(csv.Text(), "run.csv").status();
    EXPECT_TRUE(IsRefusalAt(typed, Field(c.path)));
    const std::optional<InputLocation> where = LocationOf(parsed);
    ASSERT_TRUE(where.has_value()) << parsed;
    EXPECT_EQ(where->line, csv.RowLine(c.path == "samples[0].acc_x" ? 0 : c.row)) << c.path;
    EXPECT_EQ("samples[" + std::to_string(where->line - csv.RowLine(0)) + "]." + where->field,
              c.path);
    EXPECT_EQ(DetailOf(parsed), DetailOf(typed));
  }
}

// ---------------------------------------------------------------------------
// Locations

TEST(Refusal, CarriesItsLocationAsPayload) {
  const InputLocation where{
      .source = "C:\\runs\\odd\tname: 3.csv", .line = 4, .column = 17, .field = "acc_z"};
  const absl::Status status = Refusal(where, "detail");
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(MessageOf(status), "C:\\runs\\odd\tname: 3.csv:4:17: acc_z: detail");
  EXPECT_EQ(LocationOf(status), where);
}

TEST(Refusal, LeavesOutLineAndColumnWhenZero) {
  EXPECT_EQ(MessageOf(Refusal({.source = "run.csv", .line = 7, .field = "gyro_y"}, "missing")),
            "run.csv:7: gyro_y: missing");
  EXPECT_EQ(MessageOf(Refusal({.source = "upload", .field = "samples"}, "none")),
            "upload: samples: none");
}

TEST(LocationOf, IsEmptyForOtherStatuses) {
  EXPECT_FALSE(LocationOf(absl::OkStatus()).has_value());
  EXPECT_FALSE(LocationOf(absl::InvalidArgumentError("run.csv:1:1: t: x")).has_value());
}

}  // namespace
}  // namespace insdiag::benchrun
