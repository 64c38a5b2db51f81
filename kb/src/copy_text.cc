#include "insdiag/kb/copy_text.h"

#include <charconv>
#include <cmath>

#include "store_util.h"

namespace insdiag::kb {
namespace {

constexpr char kHex[] = "0123456789abcdef";
constexpr std::int64_t kMicrosPerDay = 86'400'000'000LL;

void AppendHex(std::uint64_t value, int digits, std::string& out) {
  for (int i = digits - 1; i >= 0; --i) out.push_back(kHex[(value >> (4 * i)) & 0xfU]);
}

// The civil date of a day count since 1970-01-01 (H. Hinnant, "chrono-
// compatible low-level date algorithms", civil_from_days).
void CivilFromDays(std::int64_t z, int& y, unsigned& m, unsigned& d) {
  z += 719468;
  const std::int64_t era = (z >= 0 ? z : z - 146096) / 146097;
  const unsigned doe = static_cast<unsigned>(z - era * 146097);
  const unsigned yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const unsigned doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const unsigned mp = (5 * doy + 2) / 153;
  d = doy - (153 * mp + 2) / 5 + 1;
  m = mp < 10 ? mp + 3 : mp - 9;
  y = static_cast<int>(yoe + era * 400) + (m <= 2 ? 1 : 0);
}

void AppendDigits(std::int64_t value, int width, std::string& out) {
  char buffer[24];
  int n = 0;
  do {
    buffer[n++] = static_cast<char>('0' + value % 10);
    value /= 10;
  } while (value > 0 || n < width);
  while (n > 0) out.push_back(buffer[--n]);
}

}  // namespace

std::string UuidText(const Uuid& id) {
  std::string out;
  out.reserve(36);
  AppendHex(id.hi >> 32, 8, out);
  out.push_back('-');
  AppendHex(id.hi >> 16, 4, out);
  out.push_back('-');
  AppendHex(id.hi, 4, out);
  out.push_back('-');
  AppendHex(id.lo >> 48, 4, out);
  out.push_back('-');
  AppendHex(id.lo, 12, out);
  return out;
}

std::string TimestampTextOfMicros(std::int64_t micros) {
  std::int64_t days = micros / kMicrosPerDay;
  std::int64_t rest = micros % kMicrosPerDay;
  if (rest < 0) {
    rest += kMicrosPerDay;
    --days;
  }
  int y = 0;
  unsigned m = 0, d = 0;
  CivilFromDays(days, y, m, d);
  std::string out;
  out.reserve(30);
  AppendDigits(y, 4, out);
  out.push_back('-');
  AppendDigits(m, 2, out);
  out.push_back('-');
  AppendDigits(d, 2, out);
  out.push_back(' ');
  const std::int64_t seconds = rest / 1'000'000;
  AppendDigits(seconds / 3600, 2, out);
  out.push_back(':');
  AppendDigits(seconds / 60 % 60, 2, out);
  out.push_back(':');
  AppendDigits(seconds % 60, 2, out);
  out.push_back('.');
  AppendDigits(rest % 1'000'000, 6, out);
  out += "+00";
  return out;
}

void CopyRow::Separate() {
  if (!first_) out_.push_back('\t');
  first_ = false;
}

CopyRow& CopyRow::Null() {
  Separate();
  out_ += "\\N";
  return *this;
}

CopyRow& CopyRow::Text(std::string_view text) {
  Separate();
  for (const char c : text) {
    switch (c) {
      case '\\': out_ += "\\\\"; break;
      case '\t': out_ += "\\t"; break;
      case '\n': out_ += "\\n"; break;
      case '\r': out_ += "\\r"; break;
      default: out_.push_back(c);
    }
  }
  return *this;
}

CopyRow& CopyRow::Int(std::int64_t value) {
  Separate();
  char buffer[24];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  out_.append(buffer, end);
  return *this;
}

CopyRow& CopyRow::Double(double value) {
  if (!std::isfinite(value)) return Null();
  Separate();
  char buffer[32];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  out_.append(buffer, end);
  return *this;
}

CopyRow& CopyRow::Bool(bool value) {
  Separate();
  out_.push_back(value ? 't' : 'f');
  return *this;
}

CopyRow& CopyRow::Time(std::int64_t micros) {
  Separate();
  out_ += TimestampTextOfMicros(micros);
  return *this;
}

CopyRow& CopyRow::Id(const Uuid& id) {
  Separate();
  out_ += UuidText(id);
  return *this;
}

CopyRow& CopyRow::Bytes(std::string_view bytes) {
  Separate();
  out_ += "\\\\x";  // the bytea input "\x…", its backslash escaped for COPY
  for (const char c : bytes) {
    out_.push_back(kHex[static_cast<unsigned char>(c) >> 4]);
    out_.push_back(kHex[static_cast<unsigned char>(c) & 0xfU]);
  }
  return *this;
}

CopyRow& CopyRow::TextArray(const std::vector<std::string>& values) { return Text(internal::TextArrayLiteral(values)); }

void CopyRow::End() {
  out_.push_back('\n');
  first_ = true;
}

}  // namespace insdiag::kb
