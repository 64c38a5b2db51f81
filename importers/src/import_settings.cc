#include "insdiag/importers/import_settings.h"

#include <fstream>
#include <sstream>

#include "text_fields.h"

namespace insdiag::importers {

using internal::Split;
using internal::Trim;

void ImportSettings::Set(std::string key, std::string value, benchrun::InputLocation origin) {
  settings_.push_back({std::move(key), std::move(value), std::move(origin), ""});
}

void ImportSettings::Require(std::string key, std::string because, benchrun::InputLocation origin) {
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

bool IsKeyText(std::string_view key) {
  if (key.empty()) return false;
  for (char c : key) {
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '.')) return false;
  }
  return true;
}

}  // namespace

absl::StatusOr<ImportSettings> ParseSettingsText(std::string_view text, std::string_view source_name) {
  ImportSettings settings;
  int line_number = 0;
  for (std::string_view line : Split(text, '\n')) {
    ++line_number;
    const std::string_view trimmed = Trim(line);
    if (trimmed.empty() || trimmed.front() == '#') continue;
    const benchrun::InputLocation where{std::string(source_name), line_number, 1, ""};
    const std::size_t colon = trimmed.find(':');
    if (colon == std::string_view::npos) {
      return benchrun::Refusal({where.source, line_number, 1, "line"}, "is not 'key: value'");
    }
    const std::string key(Trim(trimmed.substr(0, colon)));
    if (!IsKeyText(key)) {
      return benchrun::Refusal({where.source, line_number, 1, key},
                               "a key is lower-case ASCII letters, digits, '_' and '.'");
    }
    std::string value(Trim(trimmed.substr(colon + 1)));
    // A YAML scalar may be quoted; the quotes are not part of the value.
    if (value.size() >= 2 && (value.front() == '"' || value.front() == '\'') && value.back() == value.front()) {
      value = value.substr(1, value.size() - 2);
    }
    settings.Set(key, std::move(value), {where.source, line_number, 1, key});
  }
  return settings;
}

absl::StatusOr<ImportSettings> ReadSettingsFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(path.string() + ": cannot be read");
  std::ostringstream text;
  text << in.rdbuf();
  return ParseSettingsText(text.str(), path.string());
}

}  // namespace insdiag::importers
