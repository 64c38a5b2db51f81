// The bench-run writer (bench_run_csv.h): what it writes the reader reads
// back exactly, and what it refuses it writes nothing of.
#include "insdiag/benchrun/bench_run_csv.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <string_view>

#include "test_runs.h"

namespace insdiag::benchrun {
namespace {

using testing::CsvText;
using testing::ExpectSameRun;
using testing::IsRefusalAt;
using ::testing::HasSubstr;
using ::testing::Not;

constexpr char kSource[] = "run.csv";

// ---------------------------------------------------------------------------
// Writer

// A run with every kind of value the writer must carry exactly: random values
// of realistic size, times that are not short decimals, signed zeros, tiny and
// subnormal numbers, values at the limits.
engine::BenchRun RandomRun(std::mt19937_64& rng, bool has_temperature) {
  std::normal_distribution<double> noise(0.0, 1.0);
  std::uniform_real_distribution<double> angle(-std::numbers::pi, std::numbers::pi);
  std::uniform_real_distribution<double> latitude(-std::numbers::pi / 2, std::numbers::pi / 2);
  engine::BenchRun run;
  run.metadata.format = std::string(kFormatV1);
  run.metadata.unit_serial = "INS-2000-" + std::to_string(rng() % 10000);
  run.metadata.site = {.latitude_rad = latitude(rng),
                       .longitude_rad = angle(rng),
                       .height_m = 100.0 + 50.0 * noise(rng)};
  run.metadata.datasheet.gyro_arw_rad_rts = 1e-6 * std::abs(noise(rng));
  run.metadata.datasheet.acc_bias_tau_s = 3600.0 / 7.0;
  run.metadata.extra = {
      {"operator", "Kim Jae-won"}, {"notes", "ключ: значение, 25 °C"}, {"x1", ""}};
  run.has_temperature = has_temperature;
  const double gravity = 9.8;
  for (int k = 0; k < 300; ++k) {
    engine::ImuSample sample;
    sample.t_s = 1000.0 + (k + 1) / 100.0;
    sample.gyro_rad_s = Eigen::Vector3d(noise(rng), noise(rng), noise(rng)) * 1e-3;
    sample.acc_mps2 = Eigen::Vector3d(noise(rng), noise(rng), -gravity + noise(rng)) * 0.05 +
                      Eigen::Vector3d(0.0, 0.0, -0.95 * gravity);
    sample.ref_rpy_rad = {angle(rng), angle(rng) / 2, angle(rng)};
    sample.temp_degc = has_temperature ? 25.0 + noise(rng) : 0.0;
    run.samples.push_back(sample);
  }
  run.samples[3].gyro_rad_s = {-0.0, 4.9406564584124654e-324, 1e-300};
  // At the limits, after the first second so that the gravity check holds.
  run.samples[204].gyro_rad_s = {kMaxGyroRateRadS, -kMaxGyroRateRadS, std::nextafter(35.0, 0.0)};
  run.samples[205].acc_mps2.x() = -kMaxSpecificForceMps2;
  return run;
}

TEST(FormatBenchRun, RoundTripIsExactWithTemperature) {
  std::mt19937_64 rng(7);
  const engine::BenchRun run = RandomRun(rng, /*has_temperature=*/true);
  ASSERT_TRUE(ValidateBenchRun(run, "random").ok()) << ValidateBenchRun(run, "random");
  const std::string text = FormatBenchRun(run);
  EXPECT_THAT(
      text,
      HasSubstr("\nt,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,ref_roll,ref_pitch,ref_yaw,temp\n"));
  const absl::StatusOr<engine::BenchRun> parsed = ParseBenchRun(text, "written");
  ASSERT_TRUE(parsed.ok()) << parsed.status();
  ExpectSameRun(*parsed, run);
}

TEST(FormatBenchRun, RoundTripIsExactWithoutTemperature) {
  std::mt19937_64 rng(8);
  const engine::BenchRun run = RandomRun(rng, /*has_temperature=*/false);
  const std::string text = FormatBenchRun(run);
  EXPECT_THAT(text,
              HasSubstr("\nt,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,ref_roll,ref_pitch,ref_yaw\n"));
  EXPECT_THAT(text, Not(HasSubstr("temp")));
  const absl::StatusOr<engine::BenchRun> parsed = ParseBenchRun(text, "written");
  ASSERT_TRUE(parsed.ok()) << parsed.status();
  ExpectSameRun(*parsed, run);
}

TEST(FormatBenchRun, MetadataInStableOrder) {
  engine::BenchRun run = testing::StaticRun(2);
  run.metadata.datasheet.acc_vrw_mps_rts = 1.5e-05;
  run.metadata.datasheet.gyro_bias_tau_s = 3600;
  run.metadata.extra = {{"notes", "second"}, {"bench", "first"}};
  const std::string text = FormatBenchRun(run);
  EXPECT_EQ(text.substr(0, text.find("\nt,")),
            "# format: insdiag-bench-run/1\n"
            "# unit_serial: INS-2000-0042\n"
            "# unit_type: INS-2000\n"
            "# site_latitude_deg: 55.5672\n"
            "# site_longitude_deg: 38.15\n"
            "# site_height_m: 125\n"
            "# gyro_bias_tau: 3600\n"
            "# acc_vrw: 1.5e-05\n"
            "# notes: second\n"
            "# bench: first");
}

// Significant digits of a number's text ("-0.0012345e-5" has 5).
int SignificantDigits(std::string_view text) {
  text = text.substr(0, text.find('e'));
  const std::size_t first = text.find_first_of("123456789");
  if (first == std::string_view::npos) return 0;
  const std::size_t last = text.find_last_of("123456789");
  const auto digits = static_cast<int>(last - first + 1);
  const bool point_between = text.find('.', first) < last;
  return point_between ? digits - 1 : digits;
}

TEST(FormatBenchRun, SiteAnglesRoundTripExactly) {
  // Degrees → radians in double cannot reach every double of radians; the
  // reader converts through long double and the writer looks for a degrees
  // text that reads back to the same radians.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> latitude(-std::numbers::pi / 2, std::numbers::pi / 2);
  std::uniform_real_distribution<double> longitude(-std::numbers::pi, std::numbers::pi);
  engine::BenchRun run = testing::StaticRun(1);
  run.samples[0].acc_mps2 = {0.0, 0.0, -9.8};
  int longer_than_a_double = 0;
  constexpr int kTrials = 2000;
  for (int trial = 0; trial < kTrials; ++trial) {
    run.metadata.site.latitude_rad = latitude(rng);
    run.metadata.site.longitude_rad = longitude(rng);
    const std::string text = FormatBenchRun(run);
    const absl::StatusOr<engine::BenchRun> parsed = ParseBenchRun(text, "written");
    ASSERT_TRUE(parsed.ok()) << parsed.status();
    ASSERT_EQ(parsed->metadata.site.latitude_rad, run.metadata.site.latitude_rad) << text;
    ASSERT_EQ(parsed->metadata.site.longitude_rad, run.metadata.site.longitude_rad) << text;
    const std::size_t begin = text.find("site_latitude_deg: ") + 19;
    if (SignificantDigits(text.substr(begin, text.find('\n', begin) - begin)) > 17) {
      ++longer_than_a_double;
    }
  }
  // Nearly all fit in the 17 digits of a double's text.
  EXPECT_LT(longer_than_a_double, kTrials / 100);
}

TEST(FormatBenchRun, SiteAnglesKeepTheirShortDecimalText) {
  CsvText csv;
  csv.metadata[3] = "# site_latitude_deg: -33.8688";
  csv.metadata[4] = "# site_longitude_deg: 151.2093";
  const absl::StatusOr<engine::BenchRun> run = ParseBenchRun(csv.Text(), kSource);
  ASSERT_TRUE(run.ok()) << run.status();
  const std::string text = FormatBenchRun(*run);
  EXPECT_THAT(text, HasSubstr("# site_latitude_deg: -33.8688\n# site_longitude_deg: 151.2093\n"));
}

TEST(WriteBenchRunFile, WritesAFileTheReaderReadsBack) {
  const std::filesystem::path path =
      std::filesystem::path(::testing::TempDir()) / "benchrun_write_test.csv";
  std::mt19937_64 rng(9);
  const engine::BenchRun run = RandomRun(rng, true);
  ASSERT_TRUE(WriteBenchRunFile(run, path).ok());
  const absl::StatusOr<engine::BenchRun> read = ReadBenchRunFile(path);
  ASSERT_TRUE(read.ok()) << read.status();
  ExpectSameRun(*read, run);
  EXPECT_FALSE(std::filesystem::exists(path.string() + ".partial"));
  std::filesystem::remove(path);
}

TEST(WriteBenchRunFile, RefusesAnInvalidRunAndWritesNothing) {
  const std::filesystem::path path =
      std::filesystem::path(::testing::TempDir()) / "benchrun_write_refused.csv";
  std::filesystem::remove(path);
  engine::BenchRun run = testing::StaticRun();
  run.samples[7].gyro_rad_s.y() = 60.0;
  const absl::Status status = WriteBenchRunFile(run, path);
  EXPECT_TRUE(IsRefusalAt(status, {.source = path.string(), .field = "samples[7].gyro_y"}));
  EXPECT_FALSE(std::filesystem::exists(path));
}

}  // namespace
}  // namespace insdiag::benchrun
