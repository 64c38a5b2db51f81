// Reader and writer of the bench-run CSV format, version 1
// (shared/spec/bench-run-format.md).
//
// Every refusal names the source, the 1-based line and the 1-based character
// column where the offending field starts, and the field (column or metadata
// key): "run.csv:12:23: gyro_z: 'abc' is not a number". The same location is
// attached to the Status as a structured payload (see InputLocation) so that
// the server can turn it into a google.rpc.BadRequest field violation.
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "insdiag/engine/bench_run.h"

namespace insdiag::benchrun {

inline constexpr std::string_view kFormatV1 = "insdiag-bench-run/1";

// Where a refused input is wrong. line/column are 0 when not applicable
// (e.g. a missing column names the header line and column 0; a gRPC upload
// names `field` as "samples[1234].gyro_x" and leaves line/column 0).
struct InputLocation {
  std::string source;
  int line = 0;
  int column = 0;
  std::string field;
};

// The location a refusal carries, if the Status came from this library.
std::optional<InputLocation> LocationOf(const absl::Status& status);

// Parses a whole bench-run CSV text. `source_name` names the input in errors.
absl::StatusOr<engine::BenchRun> ParseBenchRun(std::string_view text, std::string_view source_name);

// Reads and parses a file; errors name the file's path.
absl::StatusOr<engine::BenchRun> ReadBenchRunFile(const std::filesystem::path& path);

// Writes the run in the CSV format, doubles in shortest round-trip form so
// that ParseBenchRun(FormatBenchRun(run)) == run.
std::string FormatBenchRun(const engine::BenchRun& run);
absl::Status WriteBenchRunFile(const engine::BenchRun& run, const std::filesystem::path& path);

}  // namespace insdiag::benchrun
