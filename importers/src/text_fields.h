// Small text helpers of the importers, on std::string_view (Debian's abseil
// has its own string_view, which std::string_view does not convert to).
#pragma once

#include <charconv>
#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

namespace insdiag::importers::internal {

// Without the spaces, tabs and carriage returns around it: raw logs keep a
// "\r" from CRLF files in their lines, where the bench-run reader's lines
// have none.
inline std::string_view Trim(std::string_view text) {
  const std::size_t begin = text.find_first_not_of(" \t\r");
  if (begin == std::string_view::npos) return {};
  return text.substr(begin, text.find_last_not_of(" \t\r") - begin + 1);
}

// Splits at every `separator`; with `skip_empty`, drops empty (trimmed) parts.
inline std::vector<std::string_view> Split(std::string_view text, char separator, bool skip_empty = false) {
  std::vector<std::string_view> parts;
  std::size_t begin = 0;
  while (true) {
    const std::size_t end = text.find(separator, begin);
    const std::string_view part = Trim(text.substr(begin, end == std::string_view::npos ? end : end - begin));
    if (!(skip_empty && part.empty())) parts.push_back(part);
    if (end == std::string_view::npos) return parts;
    begin = end + 1;
  }
}

template <typename Integer>
std::optional<Integer> WholeNumber(std::string_view text, int base = 10) {
  Integer value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value, base);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return value;
}

}  // namespace insdiag::importers::internal
