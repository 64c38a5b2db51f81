// The side file of `insdiag import --settings` (import_settings.h): its YAML
// and JSON forms give the same settings with the file, line and key each came
// from, and every refusal names the file, line (and column, in JSON) and key.
#include "insdiag/importers/import_settings.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "insdiag/benchrun/bench_run_validation.h"
#include "insdiag/importers/bench_run_import.h"

namespace insdiag::importers {
namespace {

using ::testing::HasSubstr;

struct KeyValueLine {
  std::string key, value;
  int line;
};

std::vector<KeyValueLine> Listed(const ImportSettings& settings) {
  std::vector<KeyValueLine> out;
  for (const Setting& s : settings.All()) out.push_back({s.key, s.value, s.origin.line});
  return out;
}

MATCHER_P3(IsSetting, key, value, line, "") {
  return arg.key == key && arg.value == value && arg.line == line;
}

constexpr char kYaml[] =
    "# bench 3, line 2\n"
    "unit_serial: INS-2000-0042\n"
    "unit_type: 'INS-2000'\n"
    "\n"
    "site_latitude_deg: 55.5672   # the table's survey\n"
    "site_longitude_deg: \"38.15\"\n"
    "site_height_m: 125\n"
    "started_at: 2025-03-04T10:15:00Z\n"
    "columns: t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z\n"
    "units: gyro=deg/h,acc=g,t=ms\n";

constexpr char kJson[] =
    "{\n"
    "  \"unit_serial\": \"INS-2000-0042\",\n"
    "  \"unit_type\": \"INS-2000\",\n"
    "  \"site_latitude_deg\": 55.5672,\n"
    "  \"site_longitude_deg\": 38.15,\n"
    "  \"site_height_m\": 125,\n"
    "  \"started_at\": \"2025-03-04T10:15:00Z\",\n"
    "  \"columns\": \"t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z\",\n"
    "  \"units\": \"gyro=deg/h,acc=g,t=ms\"\n"
    "}\n";

TEST(SideFile, YamlGivesEachSettingWithItsLine) {
  auto settings = ParseSettingsText(kYaml, "side.yaml");
  ASSERT_TRUE(settings.ok()) << settings.status();
  EXPECT_THAT(Listed(*settings),
              ::testing::ElementsAre(IsSetting("unit_serial", "INS-2000-0042", 2),
                                     IsSetting("unit_type", "INS-2000", 3),  // quotes are not the value's
                                     IsSetting("site_latitude_deg", "55.5672", 5),  // nor is a comment
                                     IsSetting("site_longitude_deg", "38.15", 6),
                                     IsSetting("site_height_m", "125", 7),
                                     IsSetting("started_at", "2025-03-04T10:15:00Z", 8),  // colons after the key's
                                     IsSetting("columns", "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z", 9),
                                     IsSetting("units", "gyro=deg/h,acc=g,t=ms", 10)));
  EXPECT_EQ(settings->Find("units")->origin, (benchrun::InputLocation{"side.yaml", 10, 1, "units"}));
}

TEST(SideFile, JsonGivesTheYamlFormsSettingsWithEachKeysLineAndColumn) {
  auto json = ParseSettingsText(kJson, "side.json");
  ASSERT_TRUE(json.ok()) << json.status();
  auto yaml = ParseSettingsText(kYaml, "side.yaml");
  ASSERT_TRUE(yaml.ok()) << yaml.status();
  ASSERT_EQ(json->All().size(), yaml->All().size());
  for (std::size_t i = 0; i < json->All().size(); ++i) {
    EXPECT_EQ(json->All()[i].key, yaml->All()[i].key);
    EXPECT_EQ(json->All()[i].value, yaml->All()[i].value) << json->All()[i].key;  // numbers as written
  }
  EXPECT_EQ(json->Find("site_height_m")->origin, (benchrun::InputLocation{"side.json", 6, 3, "site_height_m"}));

  // Escapes, true/false, a byte-order mark, and no line breaks at all.
  auto escaped = ParseSettingsText(
      "\xEF\xBB\xBF{\"notes\":\"bench \\\"B\\\"\\t\\u00b0C \\ud83d\\ude00 \xC2\xB0\",\"meta.x\":true}", "side.json");
  ASSERT_TRUE(escaped.ok()) << escaped.status();
  EXPECT_EQ(escaped->Find("notes")->value, "bench \"B\"\t\xC2\xB0" "C \xF0\x9F\x98\x80 \xC2\xB0");
  EXPECT_EQ(escaped->Find("meta.x")->value, "true");
  EXPECT_EQ(escaped->Find("meta.x")->origin.column, 48);  // code points: the raw ° is one, not two bytes
}

// Both forms import a log to the same run.
TEST(SideFile, BothFormsImportALogToTheSameRun) {
  std::string log = "time_ms,wx,wy,wz,fx,fy,fz\n";
  for (int k = 1; k <= 100; ++k) log += std::to_string(10 * k) + ",0,0,0,0,0,-1\n";
  ImportSettings skip;
  skip.Set("skip_lines", "1", {"command line", 0, 0, "--set skip_lines"});
  std::vector<std::uint64_t> lengths;
  std::vector<std::string> serials;
  for (const auto& [text, name] : {std::pair{kYaml, "side.yaml"}, std::pair{kJson, "side.json"}}) {
    auto side = ParseSettingsText(text, name);
    ASSERT_TRUE(side.ok()) << side.status();
    ImportSettings settings = *side;
    settings.Merge(skip);
    auto run = ImportBenchRun(log, "bench.csv", settings);
    ASSERT_TRUE(run.ok()) << name << ": " << run.status();
    lengths.push_back(run->samples.size());
    serials.push_back(run->metadata.unit_serial);
    EXPECT_NEAR(run->samples.back().t_s, 1.0, 1e-12);
    EXPECT_NEAR(run->samples.back().acc_mps2.z(), -9.80665, 1e-12);
    EXPECT_EQ(*run->metadata.Extra("started_at"), "2025-03-04T10:15:00Z");
  }
  EXPECT_EQ(lengths, (std::vector<std::uint64_t>{100, 100}));
  EXPECT_EQ(serials[0], serials[1]);
}

struct Refused {
  std::string text;
  std::string message;
};

TEST(SideFile, RefusalsNameTheFileLineAndKey) {
  const std::vector<Refused> yaml = {
      {"unit_serial: A\nunit serial B\n", "side.yaml:2:1: line: is not 'key: value'"},
      {"Unit_Serial: A\n", "side.yaml:1:1: Unit_Serial: a key is lower-case ASCII letters, digits, '_' and '.'"},
      {"site:\n  latitude_deg: 55.5\n", "side.yaml:1:1: site: has no value: a side file is flat"},
      {"unit_serial: A\n  site_height_m: 125\n", "side.yaml:2:1: line: is indented: a side file is flat"},
      {"unit_serial: A\nsite_height_m: 125\nunit_serial: B\n", "side.yaml:3:1: unit_serial: is given twice (first on line 1)"},
      {"units: [gyro=deg/s]\n", "side.yaml:1:1: units: holds a mapping or a list: a side file is flat"},
      {"unit_serial: 'A\n", "side.yaml:1:1: unit_serial: 'A is not a quoted value: close the quote"},
  };
  const std::vector<Refused> json = {
      {"{\n  \"site\": {\"latitude_deg\": 55.5}\n}", "side.json:2:11: site: is an object or an array: a side file is flat"},
      {"{\"units\": [\"gyro=deg/s\"]}", "side.json:1:11: units: is an object or an array"},
      {"{\n  \"unit_serial\": null\n}", "side.json:2:18: unit_serial: is null: leave the key out instead"},
      {"{\"unit_serial\": \"A\",\n \"unit_serial\": \"B\"}", "side.json:2:2: unit_serial: is given twice (first on line 1)"},
      {"{\"unit_serial\": \"A\",\n}", "side.json:2:1: settings: a ',' before '}' is not JSON: remove it"},
      {"{\"unit_serial\": \"A\"\n \"site_height_m\": 1}", "side.json:2:2: settings: expected ',' or '}' after a member"},
      {"{\"Unit\": 1}", "side.json:1:2: Unit: a key is lower-case ASCII letters"},
      {"{unit_serial: 1}", "side.json:1:2: settings: a key is a string in double quotes"},
      {"{\"site_height_m\": 12.}", "side.json:1:19: site_height_m: '12.' is not a JSON value"},
      {"{\"site_height_m\": 0x7d}", "side.json:1:19: site_height_m: '0x7d' is not a JSON value"},
      {"{\"notes\": \"line one\nline two\"}", "side.json:1:20: settings: a string holds a raw control character"},
      {"{\"notes\": \"\\q\"}", "side.json:1:13: settings: '\\q' is not a JSON escape"},
      {"{\"notes\": \"open}", "side.json:1:11: settings: the string is not closed"},
      {"{\"unit_serial\": \"A\"", "side.json:1:20: settings: the object is not closed with '}'"},
      {"{\"unit_serial\": \"A\"}\n{\"x\": 1}", "side.json:2:1: settings: text after the object's closing '}'"},
  };
  for (const auto& [cases, name] : {std::pair{&yaml, "side.yaml"}, std::pair{&json, "side.json"}}) {
    for (const Refused& c : *cases) {
      auto settings = ParseSettingsText(c.text, name);
      ASSERT_FALSE(settings.ok()) << c.text;
      EXPECT_THAT(std::string(settings.status().message()), HasSubstr(c.message)) << c.text;
      // The location rides on the status too, as the bench-run reader's does.
      EXPECT_TRUE(benchrun::LocationOf(settings.status()).has_value()) << c.text;
    }
  }
}

// A side file's setting that the import does not know is refused naming the
// file's line, as docs/IMPORT.md shows.
TEST(SideFile, AnUnknownKeyIsRefusedWithItsLine) {
  auto settings = ParseSettingsText("unit_serial: A\nsite_latitude_deg: 1\nsite_longitude_deg: 2\nsite_height_m: 3\n"
                                    "colums: t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z\n",
                                    "side.yaml");
  ASSERT_TRUE(settings.ok()) << settings.status();
  auto run = ImportBenchRun("0.01,0,0,0,0,0,-9.81\n", "log.csv", *settings);
  ASSERT_FALSE(run.ok());
  EXPECT_THAT(std::string(run.status().message()), HasSubstr("side.yaml:5:1: colums: is not a setting of an import"));
}

TEST(SideFile, AMissingFileIsNamed) {
  auto settings = ReadSettingsFile("/nonexistent/side.yaml");
  ASSERT_FALSE(settings.ok());
  EXPECT_EQ(settings.status().message(), "/nonexistent/side.yaml: cannot be read");
}

}  // namespace
}  // namespace insdiag::importers
