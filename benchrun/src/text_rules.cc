#include "insdiag/benchrun/text_rules.h"

#include <absl/strings/str_format.h>

namespace insdiag::benchrun {
namespace {

bool IsSerialCharacter(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '.' || c == '_' ||
         c == '-';
}

// The length of the well-formed UTF-8 sequence at `text[at]`, or 0.
std::size_t SequenceLength(std::string_view text, std::size_t at) {
  const auto byte = [&](std::size_t i) { return static_cast<unsigned char>(text[i]); };
  const unsigned char lead = byte(at);
  if (lead < 0x80) return 1;
  std::size_t length = 0;
  unsigned char low = 0x80, high = 0xBF;  // the second byte's range (RFC 3629 §4)
  if (lead >= 0xC2 && lead <= 0xDF) {
    length = 2;
  } else if (lead >= 0xE0 && lead <= 0xEF) {
    length = 3;
    if (lead == 0xE0) low = 0xA0;   // no overlong forms
    if (lead == 0xED) high = 0x9F;  // no surrogates
  } else if (lead >= 0xF0 && lead <= 0xF4) {
    length = 4;
    if (lead == 0xF0) low = 0x90;
    if (lead == 0xF4) high = 0x8F;  // at most U+10FFFF
  } else {
    return 0;
  }
  if (at + length > text.size()) return 0;
  if (byte(at + 1) < low || byte(at + 1) > high) return 0;
  for (std::size_t i = 2; i < length; ++i) {
    if ((byte(at + i) & 0xC0) != 0x80) return 0;
  }
  return length;
}

}  // namespace

std::string CheckUnitSerial(std::string_view serial) {
  if (serial.empty()) return "is empty";
  if (serial.size() > kMaxUnitSerialChars) {
    return absl::StrFormat("is %d characters long; a serial has at most %d", serial.size(), kMaxUnitSerialChars);
  }
  for (std::size_t i = 0; i < serial.size(); ++i) {
    if (!IsSerialCharacter(serial[i])) {
      return absl::StrFormat(
          "'%s' holds '%s' at position %d; a serial takes A-Z, a-z, 0-9, '.', '_' and '-' (it becomes "
          "units/{serial} and file names)",
          Utf8Printable(serial), Utf8Printable(serial.substr(i, 1)), i + 1);
    }
  }
  const char first = serial.front();
  if (first == '.' || first == '_' || first == '-') {
    return absl::StrFormat("'%s' starts with '%c'; a serial starts with a letter or a digit", serial, first);
  }
  return {};
}

std::optional<std::size_t> FindInvalidUtf8(std::string_view text) {
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t length = SequenceLength(text, at);
    if (length == 0) return at;
    at += length;
  }
  return std::nullopt;
}

std::string Utf8Printable(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t length = SequenceLength(text, at);
    const auto lead = static_cast<unsigned char>(text[at]);
    if (length == 0 || lead < 0x20 || lead == 0x7F) {
      out += absl::StrFormat("\\x%02X", lead);
      ++at;
      continue;
    }
    out.append(text.substr(at, length));
    at += length;
  }
  return out;
}

}  // namespace insdiag::benchrun
