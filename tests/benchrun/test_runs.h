// Valid bench runs, as text and as values, for tests to break one thing at a time.
#pragma once

#include <absl/status/status.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <string>
#include <string_view>
#include <vector>

#include "insdiag/benchrun/bench_run_validation.h"
#include "insdiag/engine/bench_run.h"

namespace insdiag::benchrun::testing {

inline constexpr long double kSiteLatitudeDeg = 55.5672L;
inline constexpr long double kSiteLongitudeDeg = 38.15L;
inline constexpr double kSiteHeightM = 125.0;
inline constexpr double kIntervalS = 0.01;

// t of row i, "0.01", "0.02", ...: fixed width up to 9.99 s.
inline std::string TimeText(std::size_t row) {
  char text[16];
  std::snprintf(text, sizeof text, "%.2f", kIntervalS * static_cast<double>(row + 1));
  return text;
}

// A static run at 100 Hz at the spec's example site, as CSV text: 6 metadata
// lines, the header on line 7, row i on line 8 + i. Every row has the same
// field widths, so a field starts at the same column on every row:
//   t 1, gyro_x 6, gyro_y 14, gyro_z 23, acc_x 32, acc_y 39, acc_z 47,
//   ref_roll 55, ref_pitch 57, ref_yaw 59, temp 61.
struct CsvText {
  std::vector<std::string> metadata = {
      "# format: insdiag-bench-run/1", "# unit_serial: INS-2000-0042", "# unit_type: INS-2000",
      "# site_latitude_deg: 55.5672",  "# site_longitude_deg: 38.15",  "# site_height_m: 125.0",
  };
  std::string header = "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,ref_roll,ref_pitch,ref_yaw,temp";
  std::vector<std::string> rows;

  explicit CsvText(std::size_t row_count = 200) {
    for (std::size_t i = 0; i < row_count; ++i) {
      rows.push_back(TimeText(i) + ",1.1e-05,-2.3e-06,-5.9e-05,0.0012,-0.0007,-9.8154,0,0,0,24.1");
    }
  }

  int HeaderLine() const { return static_cast<int>(metadata.size()) + 1; }
  int RowLine(std::size_t row) const { return HeaderLine() + 1 + static_cast<int>(row); }

  // Replaces field `column` (0-based) of row `row` with `value`.
  void SetField(std::size_t row, std::size_t column, std::string_view value) {
    std::vector<std::string> fields = Split(rows[row]);
    fields.at(column) = value;
    rows[row] = Join(fields);
  }

  std::string Text(std::string_view line_end = "\n") const {
    std::string text;
    for (const std::string& line : metadata) text.append(line).append(line_end);
    text.append(header).append(line_end);
    for (const std::string& line : rows) text.append(line).append(line_end);
    return text;
  }

  static std::vector<std::string> Split(std::string_view line) {
    std::vector<std::string> fields;
    std::size_t begin = 0;
    while (true) {
      const std::size_t comma = line.find(',', begin);
      fields.emplace_back(line.substr(begin, comma - begin));
      if (comma == std::string_view::npos) return fields;
      begin = comma + 1;
    }
  }

  static std::string Join(const std::vector<std::string>& fields) {
    std::string line;
    for (const std::string& field : fields) line.append(line.empty() ? "" : ",").append(field);
    return line;
  }
};

// Site angles as the reader converts them: through long double, so that the
// value is the one CsvText's degrees read as, to the last bit.
inline double Radians(long double degrees) {
  return static_cast<double>(degrees * (std::numbers::pi_v<long double> / 180.0L));
}

// The run CsvText describes, as a value.
inline engine::BenchRun StaticRun(std::size_t sample_count = 200) {
  engine::BenchRun run;
  run.metadata.format = std::string(kFormatV1);
  run.metadata.unit_serial = "INS-2000-0042";
  run.metadata.unit_type = "INS-2000";
  run.metadata.site = {.latitude_rad = Radians(kSiteLatitudeDeg),
                       .longitude_rad = Radians(kSiteLongitudeDeg),
                       .height_m = kSiteHeightM};
  run.has_temperature = true;
  for (std::size_t i = 0; i < sample_count; ++i) {
    run.samples.push_back({.t_s = std::strtod(TimeText(i).c_str(), nullptr),
                           .gyro_rad_s = {1.1e-05, -2.3e-06, -5.9e-05},
                           .acc_mps2 = {0.0012, -0.0007, -9.8154},
                           .temp_degc = 24.1});
  }
  return run;
}

// The message as a std::string (Debian's abseil has its own string_view).
inline std::string MessageOf(const absl::Status& status) { return std::string(status.message()); }

// Checks that `status` is a refusal at `expected` whose message starts with
// "source:line:column: field: " (line and column left out when 0).
inline ::testing::AssertionResult IsRefusalAt(const absl::Status& status,
                                              const InputLocation& expected) {
  if (status.code() != absl::StatusCode::kInvalidArgument) {
    return ::testing::AssertionFailure() << "not a refusal: " << status;
  }
  const std::optional<InputLocation> where = LocationOf(status);
  if (!where.has_value()) return ::testing::AssertionFailure() << "no location in " << status;
  if (!(*where == expected)) {
    return ::testing::AssertionFailure()
           << "refused at " << where->source << ":" << where->line << ":" << where->column << " "
           << where->field << ", expected " << expected.source << ":" << expected.line << ":"
           << expected.column << " " << expected.field << " (" << status << ")";
  }
  std::string prefix = expected.source;
  if (expected.line > 0) prefix += ":" + std::to_string(expected.line);
  if (expected.line > 0 && expected.column > 0) prefix += ":" + std::to_string(expected.column);
  prefix += ": " + expected.field + ": ";
  const std::string message = MessageOf(status);
  if (message.rfind(prefix, 0) != 0) {
    return ::testing::AssertionFailure()
           << "message '" << message << "' does not start with '" << prefix << "'";
  }
  return ::testing::AssertionSuccess();
}

// The same run to the bit: metadata, and every sample's fields.
inline void ExpectSameRun(const engine::BenchRun& actual, const engine::BenchRun& expected) {
  EXPECT_EQ(actual.metadata.format, expected.metadata.format);
  EXPECT_EQ(actual.metadata.unit_serial, expected.metadata.unit_serial);
  EXPECT_EQ(actual.metadata.unit_type, expected.metadata.unit_type);
  EXPECT_EQ(actual.metadata.site.latitude_rad, expected.metadata.site.latitude_rad);
  EXPECT_EQ(actual.metadata.site.longitude_rad, expected.metadata.site.longitude_rad);
  EXPECT_EQ(actual.metadata.site.height_m, expected.metadata.site.height_m);
  EXPECT_EQ(actual.metadata.datasheet, expected.metadata.datasheet);
  EXPECT_EQ(actual.metadata.extra, expected.metadata.extra);
  EXPECT_EQ(actual.has_temperature, expected.has_temperature);
  ASSERT_EQ(actual.samples.size(), expected.samples.size());
  for (std::size_t i = 0; i < actual.samples.size(); ++i) {
    const engine::ImuSample& a = actual.samples[i];
    const engine::ImuSample& e = expected.samples[i];
    ASSERT_EQ(a.t_s, e.t_s) << "sample " << i;
    ASSERT_EQ(a.gyro_rad_s, e.gyro_rad_s) << "sample " << i;
    ASSERT_EQ(a.acc_mps2, e.acc_mps2) << "sample " << i;
    ASSERT_EQ(a.ref_rpy_rad, e.ref_rpy_rad) << "sample " << i;
    if (expected.has_temperature) {
      ASSERT_EQ(a.temp_degc, e.temp_degc) << "sample " << i;
    }
  }
}

}  // namespace insdiag::benchrun::testing
