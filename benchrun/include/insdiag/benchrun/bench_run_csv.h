// Reader and writer of the bench-run CSV format, version 1
// (shared/spec/bench-run-format.md).
//
// Every refusal names the source, the 1-based line and the 1-based character
// column where the offending field starts, and the field (column or metadata
// key): "run.csv:12:23: gyro_z: 'abc' is not a number". The same location is
// attached to the Status as a structured payload (see InputLocation) so that
// the server can turn it into a google.rpc.BadRequest field violation.
//
// The reader refuses, besides the value rules of bench_run_validation.h (which
// it applies through the same BenchRunValidator, mapping sample indices back
// to lines and columns): a metadata line that is not `# key: value`, a key that
// is not lower-case ASCII, a duplicate key, a missing required key or column, a
// duplicate column, a number that does not parse or is NaN/infinite, a row with
// the wrong number of fields. It tolerates a UTF-8 byte-order mark, CRLF line
// ends, blank lines before the header and at the end, spaces around fields and
// values, and columns the spec does not name (ignored). The first refusal wins
// and no run is returned. Order: the text's refusals come in line order, with
// `format` checked on its own line (another format may follow another
// grammar); the other metadata value rules apply once the header has been
// read; a sample's value rules apply when its row is read; the gap rule and
// the gravity of a run shorter than 1 s after the last row.
//
// Locations: a value names its own line and column; a missing key or column
// the header line, column 0 (the line after the last without a header); a
// wrong field count the row, at the first extra field (field "row") or at the
// end of the line (field: the first missing column); a run with no samples
// the line after the header (field "samples"); the gravity rule the first
// row's acc_x. Site angles are degrees in the text and radians in the value.
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "insdiag/benchrun/bench_run_validation.h"  // InputLocation, LocationOf, ValidateBenchRun
#include "insdiag/engine/bench_run.h"

namespace insdiag::benchrun {

// Parses a whole bench-run CSV text. `source_name` names the input in errors.
absl::StatusOr<engine::BenchRun> ParseBenchRun(std::string_view text, std::string_view source_name);

// A bench-run text read as it is written (a test being recorded): the
// metadata and header first, then rows, each refused or accepted as its line
// arrives, by ParseBenchRun's rules; Finish applies the rules of the whole
// run. Blank lines among the rows are passed over.
class BenchRunLineStream {
 public:
  explicit BenchRunLineStream(std::string source_name);
  ~BenchRunLineStream();

  // The next line, without its line break.
  absl::Status AddLine(std::string_view line);
  // The header has been read: run()'s metadata and has_temperature hold.
  bool started() const { return reader_ != nullptr; }
  // The metadata, and the samples not taken yet.
  const engine::BenchRun& run() const;
  // The samples accepted since the last call.
  std::vector<engine::ImuSample> TakeSamples();
  // The text has ended.
  absl::Status Finish();

 private:
  struct Reader;
  std::string source_;
  std::string head_;  // the metadata and header lines, which the reader's names point into
  int line_number_ = 0;
  std::size_t head_lines_ = 0;
  // Blank lines the head may hold beside its metadata lines.
  static constexpr std::size_t kMaxHeadBlankLines = 1024;
  std::unique_ptr<Reader> reader_;
};

// Reads and parses a file; errors name the file's path.
absl::StatusOr<engine::BenchRun> ReadBenchRunFile(const std::filesystem::path& path);

// Writes the run in the CSV format: metadata (format, unit_serial, unit_type,
// site, datasheet, then extra in order), the header, one row per sample;
// `temp` only when the run has temperature. Doubles are in shortest round-trip
// form, site angles in the shortest degrees text that reads back to the same
// radians, so that ParseBenchRun(FormatBenchRun(run)) == run exactly for every
// run ValidateBenchRun accepts whose metadata values have no surrounding
// spaces (the reader trims them). No check is made here.
std::string FormatBenchRun(const engine::BenchRun& run);

// Validates the run (ValidateBenchRun, naming `path`) and writes it through a
// temporary file beside it; on any error `path` is left as it was.
absl::Status WriteBenchRunFile(const engine::BenchRun& run, const std::filesystem::path& path);

}  // namespace insdiag::benchrun
