// Rules for text that enters insdiag from outside — bench-run metadata,
// request fields, HTTP headers — shared by the CSV reader, the validator of
// typed uploads and the REST gateway, so that every path refuses the same
// bytes (docs/API.md, "Limits").
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace insdiag::benchrun {

// A unit serial becomes part of resource names (units/{serial}) and of file
// names (reports, exports): 1 to kMaxUnitSerialChars characters from
// [A-Za-z0-9._-], the first a letter or digit. No '/', no space, no "..".
inline constexpr std::size_t kMaxUnitSerialChars = 64;

// Why `serial` breaks the rule above; empty when it follows it.
std::string CheckUnitSerial(std::string_view serial);

// The byte offset of the first byte that does not belong to a well-formed
// UTF-8 sequence (RFC 3629: no overlong forms, no surrogates, at most
// U+10FFFF); nullopt when the whole text is UTF-8.
std::optional<std::size_t> FindInvalidUtf8(std::string_view text);

// `text` with every byte of an ill-formed UTF-8 sequence and every control
// character written as \xNN, so that a message quoting hostile input is
// valid UTF-8 (protobuf strings, JSON) and prints on one line.
std::string Utf8Printable(std::string_view text);

}  // namespace insdiag::benchrun
