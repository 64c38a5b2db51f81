// Importing a raw IMU log as a bench run (shared/spec/bench-run-format.md;
// the settings, units and presets are in docs/IMPORT.md).
//
// The steps, each refusing what it cannot do with the log's line (or binary
// record) and the field named:
//   1. read the records (text: CSV or white space, optionally only lines with
//      a prefix and a checked NovAtel CRC; binary: little-endian fields),
//      scale each column to SI and turn the sensor axes into body axes;
//   2. settle the time base: a t column (plus GPS weeks), or a rate; t is
//      moved so that the first sample ends one nominal interval after 0, and
//      the log's own time of that 0 is kept as `time_origin_s`;
//   3. turn increments into mean rates over (t[k−1], t[k]];
//   4. set the reference attitude: constant, levelled (and gyro-compassed
//      unless a heading is given) over a static window, or from columns; a
//      table-yaw column turns the initial yaw;
//   5. check the run with the bench-run rules, naming the log's lines.
#pragma once

#include <absl/status/statusor.h>

#include <filesystem>
#include <string_view>

#include "insdiag/engine/bench_run.h"
#include "insdiag/importers/import_settings.h"

namespace insdiag::importers {

// Imports the log's bytes with the settings (the preset's, if `preset` is
// set, under `settings`). `source_name` names the log in refusals.
absl::StatusOr<engine::BenchRun> ImportBenchRun(std::string_view bytes, std::string_view source_name,
                                                const ImportSettings& settings);

// Reads the file, applies the preset named by the setting `preset` if any,
// and imports it.
absl::StatusOr<engine::BenchRun> ImportBenchRunFile(const std::filesystem::path& path,
                                                    const ImportSettings& settings);

}  // namespace insdiag::importers
