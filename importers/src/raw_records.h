// Reading a raw log's records into samples in SI units and body axes, before
// the time base and the reference attitude are settled (bench_run_import.cc).
#pragma once

#include <absl/status/statusor.h>

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "insdiag/importers/import_recipe.h"

namespace insdiag::importers::internal {

struct DecodedRecords {
  // gyro/acc hold a rate or an increment, as the columns' units say; t is
  // the raw time when a column holds it, else 0. With a GPS week column, t
  // counts from the start of the first record's week: seconds of a week keep
  // their precision, seconds since 1980 (10⁹ s) would not.
  std::vector<engine::ImuSample> samples;
  std::vector<double> table_yaw_rad;  // one per sample when a column holds it
  // Where each sample came from: the 1-based line of a text log, or the
  // 0-based record index of a binary one.
  std::vector<std::int64_t> origin;
  std::optional<double> first_gps_week;
};

// Turns one record's values (one per recipe column, skipped ones ignored)
// into a sample; shared by the text and the binary reader.
class RecordDecoder {
 public:
  explicit RecordDecoder(const ImportRecipe& recipe);
  void Append(std::span<const double> values, std::int64_t origin, DecodedRecords& into) const;

 private:
  const ImportRecipe& recipe_;
  bool has_table_yaw_ = false;
};

absl::StatusOr<DecodedRecords> ReadTextRecords(std::string_view text, std::string_view source_name,
                                               const ImportRecipe& recipe);
absl::StatusOr<DecodedRecords> ReadBinaryRecords(std::string_view bytes, std::string_view source_name,
                                                 const ImportRecipe& recipe);

// NovAtel's 32-bit CRC of an ASCII log's body (the bytes between the sync
// character and '*'): the reflected polynomial 0xEDB88320, initial value 0,
// no final complement (NovAtel OEM7 Commands and Logs Reference Manual,
// "32-Bit CRC").
std::uint32_t NovatelCrc32(std::string_view body);

}  // namespace insdiag::importers::internal
