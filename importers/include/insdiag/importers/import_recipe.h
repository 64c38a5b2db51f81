// The typed form of an import's settings (import_settings.h): which column
// holds what, in which unit, how the sensor axes map to the body axes, where
// the reference attitude comes from, and the run's metadata.
//
// Units (docs/IMPORT.md): a column's unit is a rate or an increment per
// sample, optionally counts times a scale ("0.1*arcsec"):
//   gyro   rad/s deg/s deg/h | rad deg arcsec            (increments)
//   acc    m/s2 g mg         | m/s ft/s ug.s             (increments)
//   t      s ms us ns
//   ref_*, table_yaw   rad deg
//   temp   degC
// An increment is turned into the mean rate over its interval by dividing
// by t[k] − t[k−1], as the bench-run format defines its rates.
#pragma once

#include <absl/status/statusor.h>

#include <array>
#include <optional>
#include <utility>
#include <utility>
#include <string>
#include <vector>

#include "insdiag/engine/bench_run.h"
#include "insdiag/importers/import_settings.h"

namespace insdiag::importers {

// What a column of the raw log holds, once mapped.
enum class ColumnTarget {
  kSkip,
  kTime,
  kGpsWeek,  // whole GPS weeks added to t (604800 s each)
  kGyroX,
  kGyroY,
  kGyroZ,
  kAccX,
  kAccY,
  kAccZ,
  kRefRoll,
  kRefPitch,
  kRefYaw,
  kTableYaw,  // table angle about the local down axis, added to the initial yaw
  kTemp,
};

// Little-endian field types of a binary record.
enum class BinaryType { kFloat32, kFloat64, kInt16, kInt32 };

// A physical unit as a scale to SI; `increment` when the column holds the
// change over one sample (angle, velocity) rather than a rate.
struct ColumnUnit {
  double to_si = 1.0;
  bool increment = false;
  std::string text;  // as given, for the run's notes
};

struct RawColumn {
  ColumnTarget target = ColumnTarget::kSkip;
  double sign = 1.0;  // "-acc_y": the log's value is the negative of acc_y
  ColumnUnit unit;
  BinaryType binary_type = BinaryType::kFloat64;
  std::string name;  // as written in the column map, for refusals
};

enum class LogFormat { kText, kBinary };
enum class AttitudeSource { kConstant, kLevelled, kColumns };
enum class Checksum { kNone, kNovatelCrc32 };

struct TextLayout {
  std::string delimiters;  // empty: commas if the first record has one, else white space
  int skip_lines = 0;      // lines before the records (after which comments are still skipped)
  std::string comment_prefixes = "#%";
  std::string line_prefix;  // when set, only lines starting with it are records
  Checksum checksum = Checksum::kNone;
};

struct BinaryLayout {
  int header_bytes = 0;  // before the first record
  int record_bytes = 0;  // 0: the sum of the columns' sizes
  int record_lead_bytes = 0;  // bytes at the start of each record before the first column
};

struct ImportRecipe {
  LogFormat format = LogFormat::kText;
  TextLayout text;
  BinaryLayout binary;
  std::vector<RawColumn> columns;
  // Sensor axes to body axes: body axis i = sign[i] · sensor axis axis[i].
  std::array<int, 3> axis_source = {0, 1, 2};
  std::array<double, 3> axis_sign = {1.0, 1.0, 1.0};
  std::optional<double> interval_s;  // when no column holds t
  double start_time_s = 0.0;         // t of the first record's start when t is implied
  // The records kept: those whose time since the first record lies in
  // [first, second] s (a static stretch of a longer log); all when unset.
  std::optional<std::pair<double, double>> window_s;
  double g_mps2;                     // the g of the units g, mg and ug.s

  AttitudeSource attitude = AttitudeSource::kLevelled;
  Eigen::Vector3d constant_rpy_rad = Eigen::Vector3d::Zero();
  std::optional<double> heading_rad;  // levelled attitude: given, else gyro-compassed
  std::optional<double> level_window_s;  // levelled attitude: the static start used; default the whole run

  engine::BenchRunMetadata metadata;  // format, serial, type, site, datasheet, free keys
  std::string source_description;     // "psins-imu preset", for the run's notes
};

// Reads the typed recipe from the settings; refusals name the setting's
// origin and key. Every key must be known: a misspelt key is refused.
absl::StatusOr<ImportRecipe> RecipeFromSettings(const ImportSettings& settings);

// Parses one unit ("deg/s", "0.1*arcsec") for a column of `target`.
absl::StatusOr<ColumnUnit> ParseUnit(ColumnTarget target, std::string_view text, double g_mps2);

}  // namespace insdiag::importers
