// The settings of an import: how a raw IMU log becomes a bench run
// (shared/spec/bench-run-format.md; the import contract is docs/IMPORT.md).
//
// Settings are `key: value` pairs from three layers, later ones winning: a
// named preset (presets.h), a side file (flat YAML `key: value` lines, or a
// flat JSON object of the same keys), then the command line. Each setting remembers where it came from,
// so that a refusal names the side file's line or the option, as the bench-run
// reader names a file's line and column.
#pragma once

#include <absl/status/statusor.h>

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "insdiag/benchrun/bench_run_validation.h"  // InputLocation

namespace insdiag::importers {

struct Setting {
  std::string key;
  std::string value;
  benchrun::InputLocation origin;  // "--units", or "side.yaml:3"
  // Set when a layer (a preset) needs a later one to give this key: the
  // reason it is needed, refused if no later layer overrides it.
  std::string required_because;
};

class ImportSettings {
 public:
  // Adds (or overrides) one setting.
  void Set(std::string key, std::string value, benchrun::InputLocation origin);
  // Says that a later layer must give `key`, and why.
  void Require(std::string key, std::string because, benchrun::InputLocation origin);
  // Adds every setting of `other`, overriding.
  void Merge(const ImportSettings& other);

  // The winning setting of `key`, if any.
  const Setting* Find(std::string_view key) const;
  const std::vector<Setting>& All() const { return settings_; }

 private:
  std::vector<Setting> settings_;  // in order of arrival; the last of a key wins
};

// Reads a side file, one level of keys (lower-case ASCII with '_' and '.'),
// each given once; refusals name the file, line and key.
//   YAML: `key: value` lines, blank lines, `#` comments (whole lines, or after
//         a value and a space), values optionally quoted; indented lines
//         (nested mappings) and flow collections are refused.
//   JSON: a text whose first character is '{': one object (RFC 8259) whose
//         values are strings, numbers (kept as written) or true/false;
//         objects, arrays and null are refused.
absl::StatusOr<ImportSettings> ReadSettingsFile(const std::filesystem::path& path);
absl::StatusOr<ImportSettings> ParseSettingsText(std::string_view text, std::string_view source_name);

}  // namespace insdiag::importers
