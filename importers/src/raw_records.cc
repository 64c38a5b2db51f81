#include "raw_records.h"

#include <absl/strings/str_format.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstring>

#include "insdiag/benchrun/bench_run_validation.h"
#include "insdiag/benchrun/numbers.h"
#include "text_fields.h"

namespace insdiag::importers::internal {
namespace {

using benchrun::FiniteNumber;
using benchrun::Refusal;

constexpr double kSecondsPerGpsWeek = 604800.0;

}  // namespace

RecordDecoder::RecordDecoder(const ImportRecipe& recipe) : recipe_(recipe) {
  for (const RawColumn& c : recipe.columns) has_table_yaw_ |= c.target == ColumnTarget::kTableYaw;
}

void RecordDecoder::Append(std::span<const double> values, std::int64_t origin, DecodedRecords& into) const {
  engine::ImuSample sample;
  Eigen::Vector3d gyro_sensor = Eigen::Vector3d::Zero(), acc_sensor = Eigen::Vector3d::Zero();
  double table_yaw = 0.0, week = 0.0;
  for (std::size_t i = 0; i < recipe_.columns.size(); ++i) {
    const RawColumn& c = recipe_.columns[i];
    const double v = c.sign * values[i] * c.unit.to_si;
    switch (c.target) {
      case ColumnTarget::kSkip: break;
      case ColumnTarget::kTime: sample.t_s = v; break;
      case ColumnTarget::kGpsWeek: week = values[i]; break;
      case ColumnTarget::kGyroX:
      case ColumnTarget::kGyroY:
      case ColumnTarget::kGyroZ:
        gyro_sensor[static_cast<int>(c.target) - static_cast<int>(ColumnTarget::kGyroX)] = v;
        break;
      case ColumnTarget::kAccX:
      case ColumnTarget::kAccY:
      case ColumnTarget::kAccZ:
        acc_sensor[static_cast<int>(c.target) - static_cast<int>(ColumnTarget::kAccX)] = v;
        break;
      case ColumnTarget::kRefRoll: sample.ref_rpy_rad[0] = v; break;
      case ColumnTarget::kRefPitch: sample.ref_rpy_rad[1] = v; break;
      case ColumnTarget::kRefYaw: sample.ref_rpy_rad[2] = v; break;
      case ColumnTarget::kTableYaw: table_yaw = v; break;
      case ColumnTarget::kTemp: sample.temp_degc = v; break;
    }
  }
  if (!into.first_gps_week.has_value()) into.first_gps_week = week;
  sample.t_s += (week - *into.first_gps_week) * kSecondsPerGpsWeek;
  for (int body = 0; body < 3; ++body) {
    sample.gyro_rad_s[body] = recipe_.axis_sign[body] * gyro_sensor[recipe_.axis_source[body]];
    sample.acc_mps2[body] = recipe_.axis_sign[body] * acc_sensor[recipe_.axis_source[body]];
  }
  into.samples.push_back(sample);
  if (has_table_yaw_) into.table_yaw_rad.push_back(table_yaw);
  into.origin.push_back(origin);
}

std::uint32_t NovatelCrc32(std::string_view body) {
  constexpr std::uint32_t kPolynomial = 0xEDB88320u;
  std::uint32_t crc = 0;
  for (unsigned char byte : body) {
    crc ^= byte;
    for (int bit = 0; bit < 8; ++bit) crc = (crc & 1u) ? (crc >> 1) ^ kPolynomial : crc >> 1;
  }
  return crc;
}

namespace {

// Checks and strips a NovAtel ASCII log's "*xxxxxxxx" checksum.
absl::Status CheckNovatelCrc(std::string_view& line, const benchrun::InputLocation& where) {
  const std::size_t star = line.rfind('*');
  if (star == std::string_view::npos || line.size() - star - 1 != 8) {
    return Refusal(where, "has no '*' followed by an 8-digit hexadecimal CRC");
  }
  const std::optional<std::uint32_t> stated = WholeNumber<std::uint32_t>(line.substr(star + 1), 16);
  if (!stated.has_value()) {
    return Refusal(where, absl::StrFormat("'%s' is not a hexadecimal CRC", line.substr(star + 1)));
  }
  const std::uint32_t computed = NovatelCrc32(line.substr(1, star - 1));
  if (computed != *stated) {
    return Refusal(where, absl::StrFormat("CRC %08x does not match the record's (%08x): the line is corrupt",
                                          *stated, computed));
  }
  line = line.substr(0, star);
  return absl::OkStatus();
}

// The fields of one text record and where each starts (1-based character).
struct Fields {
  std::vector<std::string_view> text;
  std::vector<int> column;
};

void SplitFields(std::string_view line, std::string_view delimiters, Fields& out) {
  out.text.clear();
  out.column.clear();
  const bool collapse = delimiters.find_first_not_of(" \t") == std::string_view::npos;
  std::size_t start = 0;
  while (start <= line.size()) {
    if (collapse) {
      start = line.find_first_not_of(delimiters, start);
      if (start == std::string_view::npos) break;
    }
    std::size_t end = line.find_first_of(delimiters, start);
    if (end == std::string_view::npos) end = line.size();
    out.text.push_back(Trim(line.substr(start, end - start)));
    out.column.push_back(static_cast<int>(start) + 1);
    if (end == line.size()) break;
    start = end + 1;
  }
}

bool IsComment(std::string_view line, std::string_view prefixes) {
  return !line.empty() && prefixes.find(line.front()) != std::string_view::npos;
}

}  // namespace

absl::StatusOr<DecodedRecords> ReadTextRecords(std::string_view text, std::string_view source_name,
                                               const ImportRecipe& recipe) {
  const TextLayout& layout = recipe.text;
  const RecordDecoder decoder(recipe);
  DecodedRecords records;
  std::string delimiters = layout.delimiters;
  std::vector<double> values(recipe.columns.size(), 0.0);
  Fields fields;
  int line_number = 0;
  std::size_t position = 0;
  if (text.starts_with("\xEF\xBB\xBF")) position = 3;  // a UTF-8 byte-order mark
  while (position < text.size()) {
    std::size_t end = text.find('\n', position);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(position, end - position);
    position = end + 1;
    ++line_number;
    if (line.ends_with('\r')) line.remove_suffix(1);
    if (line_number <= layout.skip_lines) continue;
    if (!layout.line_prefix.empty()) {
      if (!line.starts_with(layout.line_prefix)) continue;  // another log of the same stream
    } else if (Trim(line).empty() || IsComment(line, layout.comment_prefixes)) {
      continue;
    }
    const benchrun::InputLocation whole_line{std::string(source_name), line_number, 1, "record"};
    if (layout.checksum == Checksum::kNovatelCrc32) {
      if (absl::Status st = CheckNovatelCrc(line, whole_line); !st.ok()) return st;
    }
    if (delimiters.empty()) delimiters = line.find(',') != std::string_view::npos ? "," : " \t";
    SplitFields(line, delimiters, fields);
    if (fields.text.size() != recipe.columns.size()) {
      return Refusal(whole_line, absl::StrFormat("has %d fields where the column map names %d",
                                                 fields.text.size(), recipe.columns.size()));
    }
    for (std::size_t i = 0; i < recipe.columns.size(); ++i) {
      const RawColumn& c = recipe.columns[i];
      if (c.target == ColumnTarget::kSkip) continue;
      const std::optional<double> value = FiniteNumber(fields.text[i]);
      if (!value.has_value()) {
        return Refusal({std::string(source_name), line_number, fields.column[i], c.name},
                       absl::StrFormat("'%s' is not a finite number", fields.text[i]));
      }
      values[i] = *value;
    }
    decoder.Append(values, line_number, records);
  }
  return records;
}

namespace {

template <typename T>
double ReadLittleEndian(const char* at) {
  T value;
  std::memcpy(&value, at, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) {
    auto bytes = std::bit_cast<std::array<unsigned char, sizeof(T)>>(value);
    std::reverse(bytes.begin(), bytes.end());
    value = std::bit_cast<T>(bytes);
  }
  return static_cast<double>(value);
}

int SizeOf(BinaryType type) {
  switch (type) {
    case BinaryType::kFloat32: return 4;
    case BinaryType::kFloat64: return 8;
    case BinaryType::kInt16: return 2;
    case BinaryType::kInt32: return 4;
  }
  return 0;
}

double ReadField(BinaryType type, const char* at) {
  switch (type) {
    case BinaryType::kFloat32: return ReadLittleEndian<float>(at);
    case BinaryType::kFloat64: return ReadLittleEndian<double>(at);
    case BinaryType::kInt16: return ReadLittleEndian<std::int16_t>(at);
    case BinaryType::kInt32: return ReadLittleEndian<std::int32_t>(at);
  }
  return 0.0;
}

}  // namespace

absl::StatusOr<DecodedRecords> ReadBinaryRecords(std::string_view bytes, std::string_view source_name,
                                                 const ImportRecipe& recipe) {
  const BinaryLayout& layout = recipe.binary;
  int fields_bytes = layout.record_lead_bytes;
  for (const RawColumn& c : recipe.columns) fields_bytes += SizeOf(c.binary_type);
  const int stride = layout.record_bytes > 0 ? layout.record_bytes : fields_bytes;
  const std::string source(source_name);
  if (stride < fields_bytes) {
    return Refusal({source, 0, 0, "record_bytes"},
                   absl::StrFormat("%d bytes cannot hold the columns' %d", stride, fields_bytes));
  }
  if (bytes.size() < static_cast<std::size_t>(layout.header_bytes)) {
    return Refusal({source, 0, 0, "header_bytes"},
                   absl::StrFormat("the file has %d bytes, fewer than its %d-byte header", bytes.size(),
                                   layout.header_bytes));
  }
  const std::size_t body = bytes.size() - layout.header_bytes;
  if (body % stride != 0) {
    return Refusal({source, 0, 0, absl::StrFormat("record %d (byte %d)", body / stride,
                                                  layout.header_bytes + body / stride * stride)},
                   absl::StrFormat("is cut short: %d bytes after the last whole %d-byte record", body % stride, stride));
  }
  const RecordDecoder decoder(recipe);
  DecodedRecords records;
  records.samples.reserve(body / stride);
  std::vector<double> values(recipe.columns.size(), 0.0);
  for (std::size_t r = 0; r < body / stride; ++r) {
    const char* at = bytes.data() + layout.header_bytes + r * stride + layout.record_lead_bytes;
    for (std::size_t i = 0; i < recipe.columns.size(); ++i) {
      const RawColumn& c = recipe.columns[i];
      values[i] = ReadField(c.binary_type, at);
      if (c.target != ColumnTarget::kSkip && !std::isfinite(values[i])) {
        return Refusal({source, 0, 0, absl::StrFormat("record %d (byte %d): %s", r, at - bytes.data(), c.name)},
                       "is not a finite number");
      }
      at += SizeOf(c.binary_type);
    }
    decoder.Append(values, static_cast<std::int64_t>(r), records);
  }
  return records;
}

}  // namespace insdiag::importers::internal
