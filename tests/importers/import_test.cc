// insdiag::importers: raw logs to bench runs. Values are checked against
// closed forms (units, axis maps, levelling on exact static samples), the
// NovAtel CRC against an independent implementation, refusals against the
// line and field they must name, and the real RLG record (data/real) against
// samples and the alignment its independently converted copy states.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <numbers>
#include <random>
#include <string>

#include "../../importers/src/raw_records.h"
#include "insdiag/benchrun/bench_run_csv.h"
#include "insdiag/engine/nav/coarse_alignment.h"
#include "insdiag/engine/nav/rotation.h"
#include "insdiag/engine/nav/wgs84.h"
#include "insdiag/importers/bench_run_import.h"
#include "insdiag/importers/import_recipe.h"

#include <absl/strings/numbers.h>
#include <absl/strings/str_format.h>

namespace insdiag::importers {
namespace {

using ::testing::HasSubstr;

constexpr double kPi = std::numbers::pi;
constexpr double kRadPerDeg = kPi / 180.0;
constexpr double kLatitudeDeg = 55.5672;

ImportSettings Settings(std::initializer_list<std::pair<std::string, std::string>> pairs) {
  ImportSettings s;
  s.Set("unit_serial", "T-1", {"test", 0, 0, "unit_serial"});
  s.Set("site_latitude_deg", std::to_string(kLatitudeDeg), {"test", 0, 0, "site"});
  s.Set("site_longitude_deg", "38.15", {"test", 0, 0, "site"});
  s.Set("site_height_m", "125", {"test", 0, 0, "site"});
  for (const auto& [k, v] : pairs) s.Set(k, v, {"test", 0, 0, k});
  return s;
}

// What a unit at rest with attitude `rpy` measures: f^b = C_n^b·[0,0,−γ],
// ω^b = C_n^b·ω_ie^n (rotation.h, wgs84.h).
struct StaticTruth {
  Eigen::Vector3d force_mps2, rate_rad_s;
};
StaticTruth AtRest(const Eigen::Vector3d& rpy) {
  const Eigen::Matrix3d C_n_b = engine::nav::EulerToDcm(rpy).transpose();
  const double lat = kLatitudeDeg * kRadPerDeg;
  const double gamma = engine::wgs84::NormalGravityMps2(lat, 125.0);
  return {C_n_b * Eigen::Vector3d(0, 0, -gamma), C_n_b * engine::wgs84::EarthRateNed(lat)};
}

TEST(ImportUnits, ScaleRatesIncrementsAndCountsToSi) {
  auto deg_h = ParseUnit(ColumnTarget::kGyroX, "deg/h", 9.8);
  ASSERT_TRUE(deg_h.ok());
  EXPECT_DOUBLE_EQ(deg_h->to_si, kPi / 180.0 / 3600.0);
  EXPECT_FALSE(deg_h->increment);
  auto counts = ParseUnit(ColumnTarget::kGyroZ, "0.1*arcsec", 9.8);
  ASSERT_TRUE(counts.ok());
  EXPECT_DOUBLE_EQ(counts->to_si, 0.1 * kPi / 180.0 / 3600.0);
  EXPECT_TRUE(counts->increment);
  auto micro_g_s = ParseUnit(ColumnTarget::kAccX, "125*ug.s", 9.780327);
  ASSERT_TRUE(micro_g_s.ok());
  EXPECT_DOUBLE_EQ(micro_g_s->to_si, 125e-6 * 9.780327);
  auto wrong = ParseUnit(ColumnTarget::kAccX, "deg/s", 9.8);
  ASSERT_FALSE(wrong.ok());
  EXPECT_THAT(wrong.status().message(), HasSubstr("m/s2, g, mg, m/s, ft/s, ug.s"));
}

// A static text log in deg/h and g, ms time, sensor axes turned, levelled
// and gyro-compassed: the attitude comes back to the closed form's precision
// over random attitudes.
TEST(ImportText, LevelsAndGyroCompassesAStaticLogInAnyUnitsAndAxes) {
  std::mt19937_64 rng(20261126);
  std::uniform_real_distribution<double> tilt(-0.5, 0.5), heading(-kPi + 1e-3, kPi - 1e-3);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Vector3d rpy(tilt(rng), tilt(rng), heading(rng));
    const StaticTruth truth = AtRest(rpy);
    // The log's sensor axes: sensor x = body y, sensor y = −body x, sensor z = body z.
    const auto sensor = [](const Eigen::Vector3d& b) { return Eigen::Vector3d(b.y(), -b.x(), b.z()); };
    const Eigen::Vector3d w = sensor(truth.rate_rad_s) / (kRadPerDeg / 3600.0);
    const Eigen::Vector3d f = sensor(truth.force_mps2) / 9.80665;
    std::string log = "time_ms;wx;wy;wz;fx;fy;fz\n";
    for (int k = 1; k <= 200; ++k) {
      log += absl::StrFormat("%d;%.17g;%.17g;%.17g;%.17g;%.17g;%.17g\n", 10 * k, w.x(), w.y(), w.z(), f.x(), f.y(), f.z());
    }
    auto run = ImportBenchRun(log, "static.txt",
                              Settings({{"columns", "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z"},
                                        {"units", "gyro=deg/h,acc=g,t=ms"},
                                        {"delimiters", ";"},
                                        {"skip_lines", "1"},
                                        {"axes", "x=-y,y=x,z=z"}}));
    ASSERT_TRUE(run.ok()) << run.status();
    ASSERT_EQ(run->samples.size(), 200u);
    EXPECT_NEAR(run->samples[0].t_s, 0.01, 1e-15);
    EXPECT_NEAR((run->samples[7].gyro_rad_s - truth.rate_rad_s).norm(), 0.0, 1e-18);
    EXPECT_NEAR((run->samples[7].acc_mps2 - truth.force_mps2).norm(), 0.0, 1e-12);
    const Eigen::Vector3d got = run->samples.back().ref_rpy_rad;
    EXPECT_NEAR(got.x(), rpy.x(), 1e-12);
    EXPECT_NEAR(got.y(), rpy.y(), 1e-12);
    EXPECT_NEAR(std::remainder(got.z() - rpy.z(), 2 * kPi), 0.0, 1e-9) << "trial " << trial;
  }
}

// With a heading given, the levelled attitude takes it as it is and only
// levels: a gyro bias that would turn the gyro-compassed heading by tens of
// degrees leaves it alone.
TEST(ImportText, LevelsWithAGivenHeadingWhateverTheGyrosSay) {
  std::mt19937_64 rng(20261127);
  std::uniform_real_distribution<double> tilt(-0.5, 0.5), heading(-179.0, 179.0);
  // 50 °/h on every axis: b / (Ω cos L) is above 1, no heading at all.
  const Eigen::Vector3d gyro_bias = Eigen::Vector3d::Constant(50.0 * kRadPerDeg / 3600.0);
  for (int trial = 0; trial < 10; ++trial) {
    const double heading_deg = heading(rng);
    const Eigen::Vector3d rpy(tilt(rng), tilt(rng), heading_deg * kRadPerDeg);
    const StaticTruth truth = AtRest(rpy);
    const Eigen::Vector3d w = truth.rate_rad_s + gyro_bias;
    std::string log;
    for (int k = 1; k <= 100; ++k) {
      log += absl::StrFormat("%.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", 0.01 * k, w.x(), w.y(), w.z(),
                             truth.force_mps2.x(), truth.force_mps2.y(), truth.force_mps2.z());
    }
    const auto import = [&](std::initializer_list<std::pair<std::string, std::string>> extra) {
      ImportSettings s = Settings({{"columns", "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z"}});
      for (const auto& [k, v] : extra) s.Set(k, v, {"test", 0, 0, k});
      return ImportBenchRun(log, "static.txt", s);
    };
    auto given = import({{"heading_deg", absl::StrFormat("%.17g", heading_deg)}});
    ASSERT_TRUE(given.ok()) << given.status();
    const Eigen::Vector3d got = given->samples.front().ref_rpy_rad;
    EXPECT_NEAR(got.x(), rpy.x(), 1e-12);
    EXPECT_NEAR(got.y(), rpy.y(), 1e-12);
    EXPECT_NEAR(std::remainder(got.z() - rpy.z(), 2 * kPi), 0.0, 1e-12) << "trial " << trial;
    EXPECT_THAT(*given->metadata.Extra("reference_attitude"), HasSubstr("heading given"));
    // The same log gyro-compassed: the bias turns the heading far off.
    auto compassed = import({});
    ASSERT_TRUE(compassed.ok()) << compassed.status();
    EXPECT_GT(std::abs(std::remainder(compassed->samples.front().ref_rpy_rad.z() - rpy.z(), 2 * kPi)), 10 * kRadPerDeg)
        << "trial " << trial;
    EXPECT_THAT(*compassed->metadata.Extra("reference_attitude"), HasSubstr("gyro-compassed"));
  }
}

// Increments per sample become the mean rate over their own interval, and a
// table-yaw column turns the yaw from its first value.
TEST(ImportText, DividesIncrementsByTheirIntervalAndTurnsYawWithTheTable) {
  const StaticTruth truth = AtRest({0.0, 0.0, 0.0});
  std::string log;
  const double t[] = {100.0, 100.01, 100.03, 100.04};  // one interval twice as long
  for (int k = 0; k < 4; ++k) {
    const double dt = k == 0 ? 0.01 : t[k] - t[k - 1];
    const Eigen::Vector3d dtheta = truth.rate_rad_s * dt, dv = truth.force_mps2 * dt;
    log += absl::StrFormat("%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%g\n", t[k], dtheta.x(), dtheta.y(), dtheta.z(),
                           dv.x(), dv.y(), dv.z(), 30.0 * k);
  }
  auto run = ImportBenchRun(log, "inc.csv",
                            Settings({{"columns", "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,table_yaw"},
                                      {"units", "gyro=rad,acc=m/s,table_yaw=deg"},
                                      {"attitude", "constant"},
                                      {"ref_yaw_deg", "170"}}));
  ASSERT_TRUE(run.ok()) << run.status();
  for (const auto& s : run->samples) {
    EXPECT_NEAR((s.gyro_rad_s - truth.rate_rad_s).norm(), 0.0, 1e-15);
    EXPECT_NEAR((s.acc_mps2 - truth.force_mps2).norm(), 0.0, 1e-9);
  }
  EXPECT_NEAR(run->samples[0].t_s, 0.01, 1e-12);
  EXPECT_NEAR(run->samples[2].t_s, 0.04, 1e-12);
  EXPECT_EQ(*run->metadata.Extra("time_origin_s"), "99.989999999999995");
  // 170° + 90° wraps to −100°.
  EXPECT_NEAR(run->samples[3].ref_rpy_rad.z(), -100.0 * kRadPerDeg, 1e-12);
}

TEST(ImportBinary, ReadsLittleEndianRecordsWithHeaderAndLeadBytes) {
  const StaticTruth truth = AtRest({0.1, -0.2, 1.0});
  constexpr double kGyroCountRad = 1e-9, kAccCountMps = 1e-6;
  constexpr double kDt = 0.005;
  std::string bytes(16, '\x7f');  // a file header
  for (int k = 0; k < 400; ++k) {
    bytes += std::string(2, '\0');  // a record's sync bytes
    const float t = static_cast<float>((k + 1) * kDt);
    bytes.append(reinterpret_cast<const char*>(&t), 4);
    for (int i = 0; i < 3; ++i) {
      const std::int32_t count = static_cast<std::int32_t>(std::lround(truth.rate_rad_s[i] * kDt / kGyroCountRad));
      bytes.append(reinterpret_cast<const char*>(&count), 4);
    }
    for (int i = 0; i < 3; ++i) {
      const std::int32_t count = static_cast<std::int32_t>(std::lround(truth.force_mps2[i] * kDt / kAccCountMps));
      bytes.append(reinterpret_cast<const char*>(&count), 4);
    }
  }
  ImportSettings s = Settings({{"log_format", "binary"},
                               {"binary_type", "i32"},
                               {"columns", "t:f32,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z"},
                               {"units", "gyro=1e-9*rad,acc=1e-6*m/s"},
                               {"interval_s", "0.005"},
                               {"header_bytes", "16"},
                               {"record_lead_bytes", "2"}});
  auto run = ImportBenchRun(bytes, "log.bin", s);
  ASSERT_TRUE(run.ok()) << run.status();
  ASSERT_EQ(run->samples.size(), 400u);
  // One count of quantisation over one interval, and float32 time.
  EXPECT_NEAR((run->samples[200].gyro_rad_s - truth.rate_rad_s).norm(), 0.0, 2 * kGyroCountRad / kDt);
  EXPECT_NEAR((run->samples[200].acc_mps2 - truth.force_mps2).norm(), 0.0, 2e-3);
  EXPECT_NEAR(run->samples.front().ref_rpy_rad.x(), 0.1, 1e-3);

  auto cut = ImportBenchRun(bytes.substr(0, bytes.size() - 5), "log.bin", s);
  ASSERT_FALSE(cut.ok());
  EXPECT_EQ(cut.status().message(),
            "log.bin: record 399 (byte 11986): is cut short: 25 bytes after the last whole 30-byte record");
}

// Little-endian int16 counts and float64 fields, the two types the record
// above does not use; a record's own padding (record_bytes) is skipped.
TEST(ImportBinary, ReadsInt16CountsAndFloat64Fields) {
  const StaticTruth truth = AtRest({0.0, 0.0, 0.3});
  constexpr double kAccCountMps2 = 1e-3, kDt = 0.01;
  std::string bytes;
  std::vector<std::int16_t> acc_counts;
  for (int i = 0; i < 3; ++i) acc_counts.push_back(static_cast<std::int16_t>(std::lround(truth.force_mps2[i] / kAccCountMps2)));
  for (int k = 0; k < 50; ++k) {
    const double t = (k + 1) * kDt;
    bytes.append(reinterpret_cast<const char*>(&t), 8);
    for (int i = 0; i < 3; ++i) bytes.append(reinterpret_cast<const char*>(&truth.rate_rad_s[i]), 8);
    for (std::int16_t c : acc_counts) bytes.append(reinterpret_cast<const char*>(&c), 2);
    bytes += std::string(2, '\xee');  // padding to 40 bytes
  }
  auto run = ImportBenchRun(bytes, "log.bin",
                            Settings({{"log_format", "binary"},
                                      {"columns", "t:f64,gyro_x:f64,gyro_y:f64,gyro_z:f64,acc_x:i16,acc_y:i16,acc_z:i16"},
                                      {"units", "acc=1e-3*m/s2"},
                                      {"record_bytes", "40"}}));
  ASSERT_TRUE(run.ok()) << run.status();
  ASSERT_EQ(run->samples.size(), 50u);
  EXPECT_EQ(run->samples[10].gyro_rad_s, truth.rate_rad_s);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(run->samples[10].acc_mps2[i], acc_counts[static_cast<size_t>(i)] * kAccCountMps2);
  EXPECT_LT(acc_counts[2], 0) << "a negative count, to check the sign";
}

// Binary logs are refused naming the record (0-based), its byte and the
// field, or the layout setting that does not fit the file.
TEST(ImportBinary, RefusalsNameTheRecordByteAndField) {
  const StaticTruth truth = AtRest({0.0, 0.0, 0.0});
  // Records of f32 t and six f32 rates: 28 bytes each, after a 4-byte header.
  const auto records = [&](int count, int bad_record, int bad_field, float bad_value) {
    std::string bytes(4, 'H');
    for (int r = 0; r < count; ++r) {
      float fields[7] = {static_cast<float>((r + 1) * 0.01)};
      for (int i = 0; i < 3; ++i) {
        fields[1 + i] = static_cast<float>(truth.rate_rad_s[i]);
        fields[4 + i] = static_cast<float>(truth.force_mps2[i]);
      }
      if (r == bad_record) fields[bad_field] = bad_value;
      bytes.append(reinterpret_cast<const char*>(fields), sizeof fields);
    }
    return bytes;
  };
  const std::string good = records(20, -1, 0, 0.0f);
  const std::vector<std::pair<std::string, std::string>> layout = {
      {"log_format", "binary"}, {"binary_type", "f32"}, {"header_bytes", "4"},
      {"columns", "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z"}};
  struct Case {
    std::string bytes;
    std::vector<std::pair<std::string, std::string>> settings;
    std::string message;
  };
  const std::vector<Case> cases = {
      {records(20, 3, 2, std::numeric_limits<float>::quiet_NaN()), {},
       "log.bin: record 3 (byte 96): gyro_y: is not a finite number"},
      {records(20, 0, 6, std::numeric_limits<float>::infinity()), {},
       "log.bin: record 0 (byte 28): acc_z: is not a finite number"},
      {records(20, 5, 0, 0.01f), {}, "log.bin: record 5: t: "},
      {good, {{"record_bytes", "20"}}, "log.bin: record_bytes: 20 bytes cannot hold the columns' 28"},
      {good.substr(0, 3), {}, "log.bin: header_bytes: the file has 3 bytes, fewer than its 4-byte header"},
      {good, {{"binary_type", "f128"}}, "test: binary_type: 'f128' is not f32, f64, i16 or i32"},
      {good, {{"columns", "t,gyro_x:f16,gyro_y,gyro_z,acc_x,acc_y,acc_z"}},
       "test: columns: 'gyro_x:f16': the type is one of f32, f64, i16, i32"},
      {good, {{"log_format", "hex"}}, "test: log_format: 'hex' is not text or binary"},
      {good, {{"header_bytes", "-4"}}, "test: header_bytes: '-4' is not a whole number ≥ 0"},
  };
  {
    ImportSettings s = Settings({});
    for (const auto& [k, v] : layout) s.Set(k, v, {"test", 0, 0, k});
    auto run = ImportBenchRun(good, "log.bin", s);
    ASSERT_TRUE(run.ok()) << "the good records: " << run.status();
    EXPECT_EQ(run->samples.size(), 20u);
  }
  for (const Case& c : cases) {
    ImportSettings s = Settings({});
    for (const auto& [k, v] : layout) s.Set(k, v, {"test", 0, 0, k});
    for (const auto& [k, v] : c.settings) s.Set(k, v, {"test", 0, 0, k});
    auto run = ImportBenchRun(c.bytes, "log.bin", s);
    ASSERT_FALSE(run.ok()) << c.message;
    EXPECT_THAT(std::string(run.status().message()), HasSubstr(c.message));
  }
}

// The CRC of NovAtel's ASCII logs, against zlib's CRC-32 turned into
// NovAtel's (initial 0, no final complement): for this body Python's
// `zlib.crc32(body, 0xffffffff) ^ 0xffffffff` is 0x2d2a4cff.
// And against the CRC a NovAtel receiver wrote on its own record
// (data/real/novatel-rawimusxa-edie.asc).
TEST(ImportNovatel, Crc32MatchesAnIndependentImplementationAndAReceiversOwn) {
  EXPECT_EQ(internal::NovatelCrc32("RAWIMUSA,1815,407772.000;1815,407771.985103333,00000077,63811,-6290,6253,7,-31,14"),
            0x2d2a4cffu);
  EXPECT_EQ(internal::NovatelCrc32("RAWIMUSXA,1692,484620.664;00,11,1692,484620.664389000,00801503,43110635,-817242,"
                                   "-202184,-215194,-41188,-9895"),
            0xa5db8c7bu);
}

struct Refused {
  std::string log;
  std::vector<std::pair<std::string, std::string>> settings;
  std::string message;
};

// A unit that rocks while the levelling window runs — it turns by 1 mrad
// about x a second after the start and back four seconds later — is
// levelled at the start, where the run begins: the gyros' pulses take the
// turned force back to the start's axes. The whole window's mean would be
// off by the share of the window spent turned (0.4 mrad).
TEST(ImportText, LevelsTheStartOfAUnitThatTurnsWhileItIsLevelled) {
  std::mt19937_64 rng(20261206);
  std::uniform_real_distribution<double> tilt(-0.3, 0.3), heading(-kPi + 1e-3, kPi - 1e-3);
  constexpr double kTurnRad = 1e-3;
  constexpr int kSamples = 1000, kTurnSample = 100, kBackSample = 500;
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::Vector3d rpy(tilt(rng), tilt(rng), heading(rng));
    const StaticTruth start = AtRest(rpy);
    // Turned by kTurnRad about body x: a fixed vector reads (I − [θ×]) v.
    const Eigen::Vector3d theta(kTurnRad, 0.0, 0.0);
    const Eigen::Vector3d force_turned = start.force_mps2 - theta.cross(start.force_mps2);
    std::string log;
    for (int k = 1; k <= kSamples; ++k) {
      const bool turned = k > kTurnSample && k <= kBackSample;
      Eigen::Vector3d w = start.rate_rad_s;
      if (k == kTurnSample + 1) w += theta / 0.01;
      if (k == kBackSample + 1) w -= theta / 0.01;
      const Eigen::Vector3d f = turned ? force_turned : start.force_mps2;
      log += absl::StrFormat("%.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", 0.01 * k, w.x(), w.y(), w.z(), f.x(),
                             f.y(), f.z());
    }
    auto run = ImportBenchRun(log, "rocking.txt", Settings({{"columns", "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z"}}));
    ASSERT_TRUE(run.ok()) << run.status();
    const Eigen::Vector3d got = run->samples.front().ref_rpy_rad;
    // The small-angle step leaves errors of order θ², 1e-6 rad.
    EXPECT_NEAR(got.x(), rpy.x(), 5e-6) << "trial " << trial;
    EXPECT_NEAR(got.y(), rpy.y(), 5e-6) << "trial " << trial;
    EXPECT_THAT(*run->metadata.Extra("reference_attitude"), HasSubstr("taken back to the start by the gyros"));
    double level_sigma_rad = 0.0;
    ASSERT_TRUE(absl::SimpleAtod(*run->metadata.Extra("reference_level_sigma_rad"), &level_sigma_rad));
    EXPECT_LT(level_sigma_rad, 0.1 * kTurnRad) << "the turn is taken back, not counted as scatter";
    EXPECT_EQ(run->metadata.Extra("reference_heading_sigma_rad"), "unknown");
  }
}

// A unit set down with a swing that rings down (1 mrad about body x at
// 3 Hz, τ 1 s) and then rests for five minutes: the gyros' mean rate holds
// the swing's whole return, 1 mrad over 300 s, which turns a heading
// gyro-compassed from it by several degrees; the rate is the integrated
// angle's fitted slope, which the transient at one end hardly moves.
TEST(ImportText, GyroCompassesAUnitThatSettlesFromASwingAtTheStart) {
  constexpr double kSwingRad = 1e-3, kRingHz = 3.0, kRingTauS = 1.0, kIntervalS = 0.01;
  constexpr int kSamples = 30'000;
  std::mt19937_64 rng(20261206);
  // Body x (the swing's axis) within 30° of east or west, where a rate
  // error about it turns the compassed heading most.
  std::uniform_real_distribution<double> heading(60.0 * kRadPerDeg, 120.0 * kRadPerDeg);
  std::bernoulli_distribution west(0.5);
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::Vector3d rpy(0.01, -0.02, west(rng) ? -heading(rng) : heading(rng));
    const StaticTruth rest = AtRest(rpy);
    auto swing = [&](double t) {
      return kSwingRad * std::exp(-t / kRingTauS) * std::cos(2.0 * kPi * kRingHz * t);
    };
    std::string log;
    Eigen::Vector3d mean_rate = Eigen::Vector3d::Zero();
    for (int k = 1; k <= kSamples; ++k) {
      const double t = kIntervalS * k;
      const Eigen::Vector3d theta(swing(t), 0.0, 0.0);
      // The sample's rate: Earth's plus the swing's change over its interval.
      const Eigen::Vector3d w = rest.rate_rad_s + Eigen::Vector3d(swing(t) - swing(t - kIntervalS), 0, 0) / kIntervalS;
      const Eigen::Vector3d f = rest.force_mps2 - theta.cross(rest.force_mps2);
      mean_rate += w / kSamples;
      log += absl::StrFormat("%.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", t, w.x(), w.y(), w.z(), f.x(), f.y(),
                             f.z());
    }
    auto run = ImportBenchRun(log, "settling.txt", Settings({{"columns", "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z"}}));
    ASSERT_TRUE(run.ok()) << run.status();
    const double got = run->samples.front().ref_rpy_rad.z();
    const double from_mean_rate = engine::nav::CoarseAlignment(rest.force_mps2, mean_rate).z();
    EXPECT_GT(std::abs(std::remainder(from_mean_rate - rpy.z(), 2 * kPi)), 0.5 * kRadPerDeg)
        << "the case must tell the fitted slope from the mean rate, trial " << trial;
    EXPECT_LT(std::abs(std::remainder(got - rpy.z(), 2 * kPi)), 0.1 * kRadPerDeg) << "trial " << trial;
  }
}

// A consumer gyro's bias (0.05 rad/s, hundreds of times Earth's rate) gives
// no heading: the import levels, leaves the heading at 0 and says the bench
// did not survey it, rather than refusing the unit.
TEST(ImportText, LevelsAConsumerUnitAndLeavesItsHeadingUnsurveyed) {
  const Eigen::Vector3d rpy(0.02, -0.01, 1.0);
  const StaticTruth truth = AtRest(rpy);
  const Eigen::Vector3d w = truth.rate_rad_s + Eigen::Vector3d(0.05, -0.03, 0.02);
  std::string log;
  for (int k = 1; k <= 200; ++k) {
    log += absl::StrFormat("%.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", 0.01 * k, w.x(), w.y(), w.z(),
                           truth.force_mps2.x(), truth.force_mps2.y(), truth.force_mps2.z());
  }
  auto run = ImportBenchRun(log, "mems.txt", Settings({{"columns", "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z"}}));
  ASSERT_TRUE(run.ok()) << run.status();
  const Eigen::Vector3d got = run->samples.front().ref_rpy_rad;
  EXPECT_NEAR(got.x(), rpy.x(), 1e-12);
  EXPECT_NEAR(got.y(), rpy.y(), 1e-12);
  EXPECT_EQ(got.z(), 0.0);
  EXPECT_THAT(*run->metadata.Extra("reference_attitude"), HasSubstr("heading 0"));
  EXPECT_EQ(run->metadata.Extra("reference_heading_sigma_rad"), "unknown");
}

// window_s keeps the records whose time since the first lies in it, with a
// t column and with t implied by the rate alike.
TEST(ImportText, KeepsTheRecordsOfTheWindow) {
  std::string timed, untimed;
  for (int k = 0; k < 100; ++k) {
    timed += absl::StrFormat("%.17g,0,0,0,0,0,-9.81\n", 5.0 + 0.01 * k);
    untimed += "0,0,0,0,0,-9.81\n";
  }
  auto with_t = ImportBenchRun(timed, "timed.csv", Settings({{"columns", "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z"},
                                                             {"window_s", "0.2,0.5"}}));
  ASSERT_TRUE(with_t.ok()) << with_t.status();
  EXPECT_EQ(with_t->samples.size(), 31u);
  auto implied = ImportBenchRun(untimed, "untimed.csv", Settings({{"columns", "gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z"},
                                                                  {"rate_hz", "100"},
                                                                  {"window_s", "0.2,0.5"}}));
  ASSERT_TRUE(implied.ok()) << implied.status();
  EXPECT_EQ(implied->samples.size(), 31u);
}

TEST(ImportRefusals, NameTheLineAndFieldOrTheSetting) {
  const std::string good = "0.01,0,0,0,0,0,-9.81\n";
  const std::string columns = "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z";
  const std::vector<Refused> cases = {
      {good + "0.02,0,abc,0,0,0,-9.81\n", {{"columns", columns}}, "log.csv:2:8: gyro_y: 'abc' is not a finite number"},
      {good + "0.02,0,0,0,0,-9.81\n", {{"columns", columns}}, "log.csv:2:1: record: has 6 fields where the column map names 7"},
      {good + "0.01,0,0,0,0,0,-9.81\n", {{"columns", columns}}, "log.csv:2: t: 0.01 does not follow 0.01: t must increase"},
      {good, {{"columns", columns}, {"axes", "x=y,y=x,z=z"}}, "test: axes: turns a right-handed frame into a left-handed one"},
      {good, {{"columns", "t,gyro_x,gyro_y,acc_x,acc_y,acc_z"}}, "test: columns: no column is gyro_z"},
      {good, {{"columns", columns}, {"colums", "x"}}, "test: colums: is not a setting of an import"},
      {good, {{"columns", columns}, {"units", "gyro=deg/s,acc_z=m/s"}}, "the acc columns mix rates and increments"},
      {good, {{"columns", columns}, {"units", "gyro=furlong"}}, "'furlong' is not a unit of gyro_x"},
      {good + "0.02,0,0,0,0,0,-9.81\n0.03,0,0,0,0,0.86,-9.77\n0.04,0,0,0,0,0.86,-9.77\n", {{"columns", columns}},
       "settings: level_window_s: the specific force turns by 2.5"},
      {good + "0.02,0,0,0,0,0,-9.81\n", {{"columns", columns}, {"window_s", "5,6"}},
       "settings: window_s: keeps 0 record(s) of 2"},
      {good, {{"columns", columns}, {"window_s", "6,5"}}, "test: window_s: '6,5' is not FROM,TO"},
      {"0.01,0,0,0,0,0,-1.0\n", {{"columns", columns}, {"attitude", "constant"}}, "log.csv:1: acc_x: "},
      {"%RAWIMUSA,1815,407772.000;1815,407771.985103333,00000077,63811,-6290,6253,7,-31,14*2d2a4cfe\n",
       {{"columns", "-,-,-,gps_week,t,-,acc_z,-acc_y,acc_x,gyro_z,-gyro_y,gyro_x"},
        {"line_prefix", "%RAWIMUSA,"},
        {"checksum", "novatel-crc32"},
        {"delimiters", ",;"}},
       "log.csv:1:1: record: CRC 2d2a4cfe does not match the record's (2d2a4cff): the line is corrupt"},
  };
  for (const Refused& c : cases) {
    ImportSettings s = Settings({});
    for (const auto& [k, v] : c.settings) s.Set(k, v, {"test", 0, 0, k});
    auto run = ImportBenchRun(c.log, "log.csv", s);
    ASSERT_FALSE(run.ok()) << c.message;
    EXPECT_THAT(std::string(run.status().message()), HasSubstr(c.message));
  }
}

TEST(ImportRefusals, AskForWhatThePresetCannotKnow) {
  ImportSettings s;
  s.Set("preset", "novatel-rawimusa", {"command line", 0, 0, "--preset"});
  const std::filesystem::path log = std::filesystem::temp_directory_path() / "insdiag_import_rawimusa.txt";
  {
    std::FILE* f = std::fopen(log.c_str(), "w");
    std::fputs("%RAWIMUSA,1815,407772.000;1815,407771.985103333,00000077,63811,-6290,6253,7,-31,14*2d2a4cff\n", f);
    std::fclose(f);
  }
  auto run = ImportBenchRunFile(log, s);
  ASSERT_FALSE(run.ok());
  EXPECT_THAT(std::string(run.status().message()), HasSubstr("units: is required: the counts' scales depend on the IMU"));
  s.Set("units", "gyro=1e-9*rad,acc=1e-6*m/s", {"command line", 0, 0, "--units"});
  run = ImportBenchRunFile(log, s);
  ASSERT_FALSE(run.ok());
  EXPECT_THAT(std::string(run.status().message()), HasSubstr("settings: unit_serial: is missing"));
  std::filesystem::remove(log);
}

// The real ring-laser-gyro record, rebuilt in the PSINS layout: the preset
// reads the site and scales from its header, and the levelled attitude is the
// one its converted copy states (shared/data/real/README.md:
// roll 0.358°, pitch 0.927°, heading 88.59°). Every sample against numpy's
// own conversion of the counts: tests/importers/import_real_check.py.
TEST(ImportPsins, TheRealRecordImportsWithItsPublishedAlignment) {
  ImportSettings s;
  s.Set("preset", "psins-imu", {"command line", 0, 0, "--preset"});
  s.Set("unit_serial", "PSINS-RLG-2014", {"command line", 0, 0, "--serial"});
  auto run = ImportBenchRunFile(INSDIAG_SOURCE_DIR "/data/real/rlg-static-psins.imu", s);
  ASSERT_TRUE(run.ok()) << run.status();
  ASSERT_EQ(run->samples.size(), 184718u);
  EXPECT_NEAR(run->DurationS(), 1847.18, 1e-9);
  // The converted copy levels the whole run's mean attitude (roll 0.358°,
  // pitch 0.927°, heading 88.59°); the import levels the start, which the
  // unit, on a vehicle at rest, left by the milliradians its gyros measured:
  // within three of the level accuracy the import states.
  const Eigen::Vector3d rpy_deg = run->samples.front().ref_rpy_rad / kRadPerDeg;
  double level_sigma_rad = 0.0;
  ASSERT_TRUE(absl::SimpleAtod(*run->metadata.Extra("reference_level_sigma_rad"), &level_sigma_rad));
  EXPECT_GT(level_sigma_rad, 0.0);
  EXPECT_NEAR(rpy_deg.x(), 0.358, 3.0 * level_sigma_rad / kRadPerDeg);
  EXPECT_NEAR(rpy_deg.y(), 0.927, 3.0 * level_sigma_rad / kRadPerDeg);
  // The heading is no survey's: the copy's 88.59° is the whole run's mean
  // rate compassed, which the vehicle's knocks (a 4.3 mrad turn at 164 s
  // that stays) bias by about 2°; the record's header states yaw −90.6°
  // (PSINS: counter-clockwise from north, a heading of 90.6°) beside a pitch
  // and roll of 0 that the levelling shows are not the unit's, so it is a
  // rough statement too. The import's steady rate (the integrated angle's
  // fitted slope) lies between them, within 1.5° of the header.
  EXPECT_NEAR(rpy_deg.z(), 90.6, 1.5);
  EXPECT_GT(rpy_deg.z(), 88.59);
  EXPECT_EQ(run->metadata.Extra("reference_heading_sigma_rad"), "unknown");
  EXPECT_NEAR(run->metadata.site.latitude_rad / kRadPerDeg, 34.246048, 1e-12);


  // Samples as the converted copy the project was given prints them
  // (shared/data/real/rlg-static-psins.csv, converted independently of this
  // importer; ten significant digits): rows 1, 11, 100000 and the last.
  struct ConvertedRow {
    std::size_t row;
    double gyro[3], acc[3];
  };
  constexpr ConvertedRow kConverted[] = {
      {1, {0.0, 0.0, -9.696273622e-05}, {0.0, 0.0, -9.780327000e+00}},
      {11, {-3.393695768e-04, 0.0, 2.424068406e-04}, {0.0, 0.0, -9.658072912e+00}},
      {100000, {-4.363323130e-04, -4.848136811e-04, 0.0}, {1.222540875e-01, 0.0, -9.780327000e+00}},
      {184718, {-1.939254724e-04, 9.696273622e-05, -3.393695768e-04}, {2.445081750e-01, 0.0, -9.780327000e+00}},
  };
  for (const ConvertedRow& c : kConverted) {
    const engine::ImuSample& got = run->samples[c.row - 1];
    EXPECT_NEAR(got.t_s, 0.01 * static_cast<double>(c.row), 1e-9);
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(got.gyro_rad_s[i], c.gyro[i], 5e-14) << "row " << c.row << " gyro " << i;
      EXPECT_NEAR(got.acc_mps2[i], c.acc[i], 5e-9) << "row " << c.row << " acc " << i;
    }
  }
}

}  // namespace
}  // namespace insdiag::importers
