// Hostile bench runs: metadata bombs, over-long lines and keys, text that is
// not UTF-8, serials that cannot be resource names. Each is refused early,
// naming the line and column (CSV) or the field (typed upload), on both the
// reader's and the validator's path.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>

#include "insdiag/benchrun/bench_run_csv.h"
#include "insdiag/benchrun/text_rules.h"
#include "test_runs.h"

namespace insdiag::benchrun {
namespace {

using ::testing::HasSubstr;
using testing::CsvText;
using testing::StaticRun;

constexpr char kSource[] = "bomb.csv";

absl::Status ParseStatus(const std::string& text) { return ParseBenchRun(text, kSource).status(); }

InputLocation Where(const absl::Status& status) {
  const auto where = LocationOf(status);
  EXPECT_TRUE(where.has_value()) << status;
  return where.value_or(InputLocation{});
}

// N free keys after the spec's 6 metadata lines: key k on line 7 + k.
CsvText WithFreeKeys(std::size_t count) {
  CsvText csv(20);
  for (std::size_t k = 0; k < count; ++k) csv.metadata.push_back("# note_" + std::to_string(k) + ": value");
  return csv;
}

TEST(BenchRunLimits, AtTheKeyLimitARunIsRead) {
  auto run = ParseBenchRun(WithFreeKeys(kMaxFreeMetadataKeys).Text(), kSource);
  ASSERT_TRUE(run.ok()) << run.status();
  EXPECT_EQ(run->metadata.extra.size(), kMaxFreeMetadataKeys);
}

TEST(BenchRunLimits, AThirtyThousandKeyRunIsRefusedAtTheFirstKeyBeyondTheLimitWithinTwoSeconds) {
  const std::string text = WithFreeKeys(30'000).Text();
  const auto start = std::chrono::steady_clock::now();
  const absl::Status status = ParseStatus(text);
  const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - start;
  EXPECT_LT(elapsed.count(), 2.0);
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(status.message()), HasSubstr("at most 256"));
  const InputLocation where = Where(status);
  EXPECT_EQ(where.line, 7 + static_cast<int>(kMaxFreeMetadataKeys));
  EXPECT_EQ(where.field, "note_256");
}

TEST(BenchRunLimits, DuplicateKeysAreFoundInLinearTimeAndNamedWithTheirFirstLine) {
  CsvText csv = WithFreeKeys(200);
  csv.metadata.push_back("# note_3: again");
  const absl::Status status = ParseStatus(csv.Text());
  EXPECT_THAT(std::string(status.message()), HasSubstr("duplicate metadata key (first at line 10)"));
  EXPECT_EQ(Where(status).line, 7 + 200);
}

TEST(BenchRunLimits, LongKeysValuesAndLinesAreRefusedNamingTheirPlace) {
  CsvText long_key;
  long_key.metadata.push_back("# " + std::string(kMaxMetadataKeyBytes + 1, 'k') + ": v");
  EXPECT_THAT(std::string(ParseStatus(long_key.Text()).message()), HasSubstr("bomb.csv:7:3: metadata: key of 65 bytes"));

  CsvText long_value;
  long_value.metadata.push_back("# notes: " + std::string(kMaxMetadataValueBytes + 10, 'v'));
  const absl::Status value = ParseStatus(long_value.Text());
  EXPECT_THAT(std::string(value.message()), HasSubstr("notes: value of 4106 bytes is longer than 4096 bytes"));
  EXPECT_EQ(Where(value).line, 7);

  CsvText long_row;
  long_row.rows[5] += std::string(kMaxLineBytes, ' ');
  const absl::Status row = ParseStatus(long_row.Text());
  EXPECT_THAT(std::string(row.message()), HasSubstr("row: line of"));
  EXPECT_EQ(Where(row).line, long_row.RowLine(5));
  EXPECT_EQ(Where(row).column, static_cast<int>(kMaxLineBytes) + 1);
}

TEST(BenchRunLimits, AMetadataValueThatIsNotUtf8IsRefusedAtItsByte) {
  CsvText csv;
  csv.metadata.push_back("# operator: caf\xff");
  const absl::Status status = ParseStatus(csv.Text());
  EXPECT_THAT(std::string(status.message()), HasSubstr("bomb.csv:7:16: operator: byte 0xFF is not UTF-8 text"));
  // The message itself is UTF-8: it travels in protobuf strings and JSON.
  EXPECT_FALSE(FindInvalidUtf8(std::string(status.message())).has_value());
}

TEST(BenchRunLimits, SerialsThatCannotBeResourceNamesAreRefused) {
  for (const char* serial : {"INS/2000", "../etc", "-INS", "INS 2000", "INS\xc3\xa9"}) {
    CsvText csv;
    csv.metadata[1] = std::string("# unit_serial: ") + serial;
    const absl::Status status = ParseStatus(csv.Text());
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << serial;
    EXPECT_EQ(Where(status).field, "unit_serial") << serial;
    EXPECT_EQ(Where(status).line, 2) << serial;
  }
  EXPECT_EQ(CheckUnitSerial("INS-2000_0042.b"), "");
  EXPECT_THAT(CheckUnitSerial(std::string(kMaxUnitSerialChars + 1, 'A')), HasSubstr("at most 64"));
}

// The typed upload's path: the same limits, named by field path.
TEST(BenchRunLimits, TheValidatorAppliesTheLimitsToTypedUploads) {
  engine::BenchRun run = StaticRun();
  for (std::size_t k = 0; k <= kMaxFreeMetadataKeys; ++k) run.metadata.extra.emplace_back(std::string("k").append(std::to_string(k)), "v");
  EXPECT_THAT(std::string(ValidateBenchRun(run, "upload").message()),
              HasSubstr("upload: metadata.extra[256]: 257 free metadata keys; a run holds at most 256"));

  run = StaticRun();
  run.metadata.extra.emplace_back("operator", "caf\xff");
  EXPECT_THAT(std::string(ValidateBenchRun(run, "upload").message()),
              HasSubstr("upload: metadata.extra[0]: 'operator': byte 0xFF at byte 4 of the value is not UTF-8"));

  run = StaticRun();
  run.metadata.extra.emplace_back("notes", std::string(kMaxMetadataValueBytes + 1, 'v'));
  EXPECT_THAT(std::string(ValidateBenchRun(run, "upload").message()), HasSubstr("value of 4097 bytes"));

  run = StaticRun();
  run.metadata.unit_serial = "units/INS-1";
  EXPECT_THAT(std::string(ValidateBenchRun(run, "upload").message()), HasSubstr("upload: metadata.unit_serial: 'units/INS-1' holds '/'"));
}

TEST(BenchRunLimits, TheLineStreamBoundsItsHead) {
  BenchRunLineStream stream("live");
  absl::Status status;
  for (int k = 0; status.ok() && k < 100'000; ++k) status = stream.AddLine("# key_" + std::to_string(k) + ": v");
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(status.message()), HasSubstr("at most 256"));

  BenchRunLineStream long_line("live");
  EXPECT_THAT(std::string(long_line.AddLine("# notes: " + std::string(kMaxLineBytes, 'v')).message()),
              HasSubstr("live:1:8193: metadata: line of"));
}

TEST(TextRules, FindsIllFormedUtf8AndEscapesItForMessages) {
  EXPECT_FALSE(FindInvalidUtf8("caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80").has_value());
  EXPECT_EQ(FindInvalidUtf8("ab\xc0\xaf"), 2u);        // overlong '/'
  EXPECT_EQ(FindInvalidUtf8("\xed\xa0\x80"), 0u);      // a surrogate
  EXPECT_EQ(FindInvalidUtf8("ok\xe2\x82"), 2u);        // cut short
  EXPECT_EQ(Utf8Printable("a\xff\nb\xc3\xa9"), "a\\xFF\\x0Ab\xc3\xa9");
}

}  // namespace
}  // namespace insdiag::benchrun
