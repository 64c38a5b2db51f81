#include "insdiag/importers/import_settings.h"

#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include "insdiag/engine/status_macros.h"
#include "text_fields.h"

namespace insdiag::importers {

using benchrun::InputLocation;
using benchrun::Refusal;
using internal::Trim;

void ImportSettings::Set(std::string key, std::string value, InputLocation origin) {
  settings_.push_back({std::move(key), std::move(value), std::move(origin), ""});
}

void ImportSettings::Require(std::string key, std::string because, InputLocation origin) {
  settings_.push_back({std::move(key), "", std::move(origin), std::move(because)});
}

void ImportSettings::Merge(const ImportSettings& other) {
  for (const Setting& s : other.settings_) settings_.push_back(s);
}

const Setting* ImportSettings::Find(std::string_view key) const {
  for (auto it = settings_.rbegin(); it != settings_.rend(); ++it) {
    if (it->key == key) return &*it;
  }
  return nullptr;
}

namespace {

constexpr std::string_view kUtf8ByteOrderMark = "\xEF\xBB\xBF";
constexpr char kFlatHint[] = "a side file is flat: one level of keys, as docs/IMPORT.md lists them";

bool IsKeyText(std::string_view key) {
  if (key.empty()) return false;
  for (char c : key) {
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '.')) return false;
  }
  return true;
}

// The settings of one side file, refusing a key given twice: in a file one
// writes by hand, the second of two is more likely a slip than an override.
class SideFileSettings {
 public:
  absl::Status Add(std::string key, std::string value, InputLocation where) {
    if (const auto first = first_line_.find(key); first != first_line_.end()) {
      return Refusal(where, absl::StrFormat("is given twice (first on line %d)", first->second));
    }
    first_line_.emplace(key, where.line);
    settings_.Set(std::move(key), std::move(value), std::move(where));
    return absl::OkStatus();
  }
  ImportSettings Take() && { return std::move(settings_); }

 private:
  ImportSettings settings_;
  std::map<std::string, int, std::less<>> first_line_;
};

// The YAML form: `key: value` lines, blank lines, `#` comments (whole lines,
// or after a value and a space), values optionally in quotes.
absl::StatusOr<ImportSettings> ParseFlatYaml(std::string_view text, std::string_view source_name) {
  SideFileSettings settings;
  const std::string source(source_name);
  int line_number = 0;
  for (std::size_t begin = 0; begin < text.size();) {
    const std::size_t end = std::min(text.find('\n', begin), text.size());
    const std::string_view raw = text.substr(begin, end - begin);
    begin = end + 1;
    ++line_number;
    const std::string_view line = Trim(raw);
    if (line.empty() || line.front() == '#' || (line_number == 1 && line == "---")) continue;
    if (raw.front() == ' ' || raw.front() == '\t') {
      return Refusal({source, line_number, 1, "line"}, absl::StrCat("is indented: ", kFlatHint));
    }
    const std::size_t colon = line.find(':');
    if (colon == std::string_view::npos) return Refusal({source, line_number, 1, "line"}, "is not 'key: value'");
    const std::string key(Trim(line.substr(0, colon)));
    const InputLocation where{source, line_number, 1, key};
    if (!IsKeyText(key)) return Refusal(where, "a key is lower-case ASCII letters, digits, '_' and '.'");
    std::string_view value = Trim(line.substr(colon + 1));
    std::string unquoted;
    if (!value.empty() && (value.front() == '"' || value.front() == '\'')) {
      // A quoted scalar; the quotes are not part of the value, a comment may follow.
      const std::size_t close = value.find(value.front(), 1);
      const std::string_view after = close == std::string_view::npos ? "" : Trim(value.substr(close + 1));
      if (close == std::string_view::npos || !(after.empty() || after.front() == '#')) {
        return Refusal(where, absl::StrFormat("%s is not a quoted value: close the quote, then at most a # comment",
                                              value));
      }
      unquoted = std::string(value.substr(1, close - 1));
    } else {
      if (const std::size_t comment = value.find(" #"); comment != std::string_view::npos) {
        value = Trim(value.substr(0, comment));
      }
      if (value.empty()) return Refusal(where, absl::StrCat("has no value: ", kFlatHint));
      if (value.front() == '{' || value.front() == '[') {
        return Refusal(where, absl::StrCat("holds a mapping or a list: ", kFlatHint));
      }
      unquoted = std::string(value);
    }
    if (absl::Status st = settings.Add(key, std::move(unquoted), where); !st.ok()) return st;
  }
  return std::move(settings).Take();
}

// The JSON form (RFC 8259): one object whose members are the YAML form's
// keys, each a string, a number (kept as written) or true/false.
class FlatJsonReader {
 public:
  FlatJsonReader(std::string_view text, std::string_view source) : text_(text), source_(source) {}

  absl::StatusOr<ImportSettings> Read() {
    SkipSpace();
    if (Peek() != '{') return Refusal(Here("settings"), "a JSON side file is one object: { \"key\": value, ... }");
    Advance();
    SideFileSettings settings;
    SkipSpace();
    bool first = true;
    while (Peek() != '}') {
      if (pos_ >= text_.size()) return Refusal(Here("settings"), "the object is not closed with '}'");
      if (!first) {
        if (Peek() != ',') return Refusal(Here("settings"), "expected ',' or '}' after a member");
        Advance();
        SkipSpace();
        if (Peek() == '}') return Refusal(Here("settings"), "a ',' before '}' is not JSON: remove it");
      }
      first = false;
      InputLocation where = Here("settings");
      if (Peek() != '"') return Refusal(where, "a key is a string in double quotes");
      INSDIAG_ASSIGN_OR_RETURN(auto key, String());
      where.field = key;
      if (!IsKeyText(key))
        return Refusal(where, "a key is lower-case ASCII letters, digits, '_' and '.'");
      SkipSpace();
      if (Peek() != ':') return Refusal(Here(key), "expected ':' after the key");
      Advance();
      SkipSpace();
      INSDIAG_ASSIGN_OR_RETURN(auto value, Value(key));
      if (absl::Status st = settings.Add(key, std::move(value), where); !st.ok()) return st;
      SkipSpace();
    }
    Advance();
    SkipSpace();
    if (pos_ < text_.size()) return Refusal(Here("settings"), "text after the object's closing '}'");
    return std::move(settings).Take();
  }

 private:
  char Peek() const { return pos_ < text_.size() ? text_[pos_] : '\0'; }
  void Advance() {
    if (text_[pos_] == '\n') {
      ++line_;
      column_ = 1;
    } else if ((static_cast<unsigned char>(text_[pos_]) & 0xC0) != 0x80) {
      ++column_;  // columns count code points: UTF-8 continuation bytes add none
    }
    ++pos_;
  }
  void SkipSpace() {
    while (Peek() == ' ' || Peek() == '\t' || Peek() == '\r' || Peek() == '\n') Advance();
  }
  InputLocation Here(std::string field) const { return {source_, line_, column_, std::move(field)}; }

  // A string at '"', its escapes decoded.
  absl::StatusOr<std::string> String() {
    const InputLocation start = Here("settings");
    Advance();
    std::string out;
    while (pos_ < text_.size() && Peek() != '"') {
      const char c = Peek();
      if (static_cast<unsigned char>(c) < 0x20) {
        return Refusal(Here("settings"), "a string holds a raw control character (a line break?): escape it");
      }
      Advance();
      if (c != '\\') {
        out += c;
        continue;
      }
      const char e = Peek();
      static constexpr std::string_view kEscapes = "\"\\/bfnrt", kMeanings = "\"\\/\b\f\n\r\t";
      if (const std::size_t i = kEscapes.find(e); e != '\0' && i != std::string_view::npos) {
        out += kMeanings[i];
        Advance();
      } else if (e == 'u') {
        Advance();
        if (absl::Status st = AppendCodePoint(out); !st.ok()) return st;
      } else {
        return Refusal(Here("settings"), absl::StrFormat("'\\%c' is not a JSON escape", e));
      }
    }
    if (pos_ >= text_.size()) return Refusal(start, "the string is not closed");
    Advance();
    return out;
  }

  // After "\u": four hex digits (a surrogate pair as two), as UTF-8.
  absl::Status AppendCodePoint(std::string& out) {
    const auto hex4 = [&]() -> std::optional<std::uint32_t> {
      if (pos_ + 4 > text_.size()) return std::nullopt;
      const auto v = internal::WholeNumber<std::uint32_t>(text_.substr(pos_, 4), 16);
      if (v.has_value()) for (int i = 0; i < 4; ++i) Advance();
      return v;
    };
    const InputLocation where = Here("settings");
    std::optional<std::uint32_t> cp = hex4();
    if (cp.has_value() && *cp >= 0xD800 && *cp < 0xDC00 && text_.substr(pos_, 2) == "\\u") {
      Advance();
      Advance();
      const std::optional<std::uint32_t> low = hex4();
      const bool paired = low.has_value() && *low >= 0xDC00 && *low < 0xE000;
      cp = paired ? std::optional(0x10000 + ((*cp - 0xD800) << 10) + (*low - 0xDC00)) : std::nullopt;
    }
    if (!cp.has_value() || (*cp >= 0xD800 && *cp < 0xE000)) {
      return Refusal(where, "\\u is followed by four hexadecimal digits of a character");
    }
    if (*cp < 0x80) {
      out += static_cast<char>(*cp);
    } else if (*cp < 0x800) {
      out += static_cast<char>(0xC0 | (*cp >> 6));
      out += static_cast<char>(0x80 | (*cp & 0x3F));
    } else if (*cp < 0x10000) {
      out += static_cast<char>(0xE0 | (*cp >> 12));
      out += static_cast<char>(0x80 | ((*cp >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (*cp & 0x3F));
    } else {
      out += static_cast<char>(0xF0 | (*cp >> 18));
      out += static_cast<char>(0x80 | ((*cp >> 12) & 0x3F));
      out += static_cast<char>(0x80 | ((*cp >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (*cp & 0x3F));
    }
    return absl::OkStatus();
  }

  // A member's value as the setting's text.
  absl::StatusOr<std::string> Value(const std::string& key) {
    const InputLocation where = Here(key);
    switch (Peek()) {
      case '"': return String();
      case '{':
      case '[': return Refusal(where, absl::StrCat("is an object or an array: ", kFlatHint));
      default: break;
    }
    // A literal or a number: up to the next delimiter.
    const std::size_t begin = pos_;
    while (pos_ < text_.size() && std::string_view(",}] \t\r\n").find(Peek()) == std::string_view::npos) Advance();
    const std::string_view token = text_.substr(begin, pos_ - begin);
    if (token == "true" || token == "false") return std::string(token);
    if (token == "null") return Refusal(where, "is null: leave the key out instead");
    if (!IsJsonNumber(token)) {
      return Refusal(where, absl::StrFormat("'%s' is not a JSON value: a \"string\", a number, true or false", token));
    }
    return std::string(token);
  }

  // RFC 8259 §6: -?(0|[1-9][0-9]*)(\.[0-9]+)?([eE][+-]?[0-9]+)?
  static bool IsJsonNumber(std::string_view t) {
    std::size_t i = 0;
    const auto digits = [&]() {
      const std::size_t from = i;
      while (i < t.size() && t[i] >= '0' && t[i] <= '9') ++i;
      return i - from;
    };
    if (i < t.size() && t[i] == '-') ++i;
    if (i < t.size() && t[i] == '0') {
      ++i;
    } else if (digits() == 0) {
      return false;
    }
    if (i < t.size() && t[i] == '.') {
      ++i;
      if (digits() == 0) return false;
    }
    if (i < t.size() && (t[i] == 'e' || t[i] == 'E')) {
      ++i;
      if (i < t.size() && (t[i] == '+' || t[i] == '-')) ++i;
      if (digits() == 0) return false;
    }
    return i == t.size();
  }

  std::string_view text_;
  std::string source_;
  std::size_t pos_ = 0;
  int line_ = 1;
  int column_ = 1;
};

}  // namespace

absl::StatusOr<ImportSettings> ParseSettingsText(std::string_view text, std::string_view source_name) {
  if (text.starts_with(kUtf8ByteOrderMark)) text.remove_prefix(kUtf8ByteOrderMark.size());
  // A JSON object is also a YAML flow mapping: what starts with '{' is read as JSON.
  const std::size_t first = text.find_first_not_of(" \t\r\n");
  if (first != std::string_view::npos && text[first] == '{') return FlatJsonReader(text, source_name).Read();
  return ParseFlatYaml(text, source_name);
}

absl::StatusOr<ImportSettings> ReadSettingsFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(path.string() + ": cannot be read");
  std::ostringstream text;
  text << in.rdbuf();
  return ParseSettingsText(text.str(), path.string());
}

}  // namespace insdiag::importers
