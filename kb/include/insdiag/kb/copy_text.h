// Rows in PostgreSQL's COPY text format (tab-separated, newline-terminated,
// backslash escapes, \N for NULL), appended to the buffer that
// Connection::CopyIn (pg.h) sends: bulk loads without a statement per row.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace insdiag::kb {

// A UUID as two 64-bit halves, printed big-endian (PostgreSQL compares
// UUIDs bytewise, so increasing halves sort as increasing UUIDs).
struct Uuid {
  std::uint64_t hi = 0;
  std::uint64_t lo = 0;
};
std::string UuidText(const Uuid& id);

// UTC microseconds since the epoch as "YYYY-MM-DD HH:MM:SS.ffffff+00".
std::string TimestampTextOfMicros(std::int64_t micros);

// One COPY row at a time: fields separated by tabs, End() closes the row.
class CopyRow {
 public:
  explicit CopyRow(std::string& out) : out_(out) {}
  CopyRow& Null();
  CopyRow& Text(std::string_view text);  // escaped
  CopyRow& Int(std::int64_t value);
  CopyRow& Double(double value);  // shortest round-trip text; NULL when not finite
  CopyRow& Bool(bool value);
  CopyRow& Time(std::int64_t micros);  // timestamptz, UTC µs since the epoch
  CopyRow& Id(const Uuid& id);
  CopyRow& Bytes(std::string_view bytes);                // bytea, hex
  CopyRow& TextArray(const std::vector<std::string>& values);  // text[]
  void End();

 private:
  void Separate();
  std::string& out_;
  bool first_ = true;
};

}  // namespace insdiag::kb
