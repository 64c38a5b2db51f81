#include <absl/strings/str_format.h>

#include <algorithm>
#include <limits>
#include <array>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <unordered_map>
#include <vector>

#include "insdiag/benchrun/bench_run_csv.h"
#include "insdiag/benchrun/text_rules.h"
#include "metadata_rules.h"
#include "number_text.h"
#include "sample_fields.h"

namespace insdiag::benchrun {
namespace {

using internal::NumberParse;

constexpr std::string_view kUtf8ByteOrderMark = "\xEF\xBB\xBF";
constexpr std::array kRequiredKeys = {MetadataField::kFormat, MetadataField::kUnitSerial,
                                      MetadataField::kSiteLatitude, MetadataField::kSiteLongitude,
                                      MetadataField::kSiteHeight};

bool IsSpaceOrTab(char c) { return c == ' ' || c == '\t'; }

// Plain loops: find_first_not_of calls memchr per character, which showed up
// as a tenth of the parse time.
std::string_view Trim(std::string_view text) {
  while (!text.empty() && IsSpaceOrTab(text.front())) text.remove_prefix(1);
  while (!text.empty() && IsSpaceOrTab(text.back())) text.remove_suffix(1);
  return text;
}

bool IsBlank(std::string_view text) {
  return std::all_of(text.begin(), text.end(),
                     [](char c) { return IsSpaceOrTab(c) || c == '\r' || c == '\n'; });
}

// 1-based character column of `at` in `line`: UTF-8 continuation bytes do not
// start a character.
int CharacterColumn(std::string_view line, const char* at) {
  int column = 1;
  for (const char* p = line.data(); p < at; ++p) {
    if ((static_cast<unsigned char>(*p) & 0xC0) != 0x80) ++column;
  }
  return column;
}

// Splits the text into lines without their break ("\n" or "\r\n").
class LineReader {
 public:
  LineReader(std::string_view text, int first_line_number)
      : rest_(text), number_(first_line_number - 1) {}

  bool Next(std::string_view& line) {
    if (rest_.empty()) return false;
    const std::size_t end = rest_.find('\n');
    line = rest_.substr(0, end);
    rest_.remove_prefix(end == rest_.npos ? rest_.size() : end + 1);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    ++number_;
    return true;
  }

  int number() const { return number_; }  // of the line Next returned last
  std::string_view rest() const { return rest_; }

 private:
  std::string_view rest_;
  int number_;
};

// Where a rule's subject stands in the text. Metadata places are recorded as
// the lines are read; a sample's place is found again from its index only when
// a rule refuses it, so the fast path keeps no per-row positions: rows are
// consecutive lines, so sample i is line first_data_line + i.
class CsvLocator final : public InputLocator {
 public:
  struct Place {
    int line = 0;
    int column = 0;
  };

  explicit CsvLocator(std::string_view source) : source_(source) { header_column_of_.fill(-1); }

  InputLocation OfSample(std::size_t sample_index, SampleField field) const override {
    const int line_number = first_data_line_ + static_cast<int>(sample_index - first_sample_);
    InputLocation location{
        .source = source_, .line = line_number, .field = std::string(ColumnName(field))};
    LineReader lines(data_, first_data_line_);
    std::string_view line;
    while (lines.Next(line) && lines.number() < line_number) {
    }
    const int header_column = header_column_of_[static_cast<std::size_t>(field)];
    if (lines.number() != line_number || header_column < 0) return location;
    std::size_t begin = 0;
    for (int k = 0; k < header_column && begin != line.npos; ++k) {
      begin = line.find(',', begin);
      if (begin != line.npos) ++begin;
    }
    if (begin == line.npos) return location;
    const std::string_view text = Trim(line.substr(begin, line.find(',', begin) - begin));
    location.column = CharacterColumn(line, text.data());
    return location;
  }

  InputLocation OfMetadata(MetadataField field, std::size_t extra_index) const override {
    if (field == MetadataField::kExtra) {
      const auto& [key, place] = extra_places_.at(extra_index);
      return {
          .source = source_, .line = place.line, .column = place.column, .field = std::string(key)};
    }
    const Place& place = metadata_places_[static_cast<std::size_t>(field)];
    return {.source = source_,
            .line = place.line,
            .column = place.column,
            .field = std::string(MetadataKey(field))};
  }

  InputLocation OfSampleList() const override {
    return {.source = source_, .line = first_data_line_, .field = "samples"};
  }

  InputLocation At(int line, int column, std::string_view field) const {
    return {.source = source_, .line = line, .column = column, .field = std::string(field)};
  }

  void SetMetadataPlace(MetadataField field, Place place) {
    metadata_places_[static_cast<std::size_t>(field)] = place;
  }
  bool HasMetadata(MetadataField field) const {
    return metadata_places_[static_cast<std::size_t>(field)].line > 0;
  }
  void AddExtraPlace(std::string_view key, Place place) { extra_places_.emplace_back(key, place); }
  void RemoveExtraPlace(std::size_t extra_index) {
    extra_places_.erase(extra_places_.begin() + static_cast<std::ptrdiff_t>(extra_index));
  }
  void SetHeaderColumn(SampleField field, int header_column) {
    header_column_of_[static_cast<std::size_t>(field)] = header_column;
  }
  bool HasColumn(SampleField field) const {
    return header_column_of_[static_cast<std::size_t>(field)] >= 0;
  }
  // The rows' text from line `first_data_line` on, whose first row holds
  // sample `first_sample` (not 0 when rows are read as they arrive).
  void SetData(std::string_view data, int first_data_line, std::size_t first_sample = 0) {
    data_ = data;
    first_data_line_ = first_data_line;
    first_sample_ = first_sample;
  }

 private:
  std::string source_;
  std::array<Place, kSpecMetadataFieldCount> metadata_places_{};
  std::vector<std::pair<std::string_view, Place>> extra_places_;
  std::array<int, kSampleFieldCount> header_column_of_{};
  std::string_view data_;
  int first_data_line_ = 0;
  std::size_t first_sample_ = 0;
};

class Parser {
 public:
  Parser(std::string_view text, std::string_view source_name)
      : lines_(text.substr(text.starts_with(kUtf8ByteOrderMark) ? kUtf8ByteOrderMark.size() : 0),
               1),
        locator_(source_name) {}

  // The metadata and header; the rows follow in the text (Parse) or arrive
  // later (ReadArrivedRow).
  absl::Status ParseHead() {
    std::optional<std::string_view> header;
    if (absl::Status status = ReadMetadata(header); !status.ok()) return status;
    if (absl::Status status = CheckRequiredKeys(header.has_value()); !status.ok()) return status;
    if (!header.has_value()) {
      return Refusal(locator_.At(lines_.number() + 1, 0, "header"), "missing header row");
    }
    if (absl::Status status = ReadHeader(*header); !status.ok()) return status;
    if (absl::Status status = TakeSegmentStarts(); !status.ok()) return status;
    absl::StatusOr<BenchRunValidator> validator =
        BenchRunValidator::Create(run_.metadata, run_.has_temperature, locator_);
    if (!validator.ok()) return validator.status();
    validator_.emplace(*std::move(validator));
    return absl::OkStatus();
  }

  // One row, line `line_number` of the text, after ParseHead.
  absl::Status ReadArrivedRow(std::string_view line, int line_number) {
    lines_ = LineReader(line, line_number);
    std::string_view row;
    lines_.Next(row);
    locator_.SetData(line, line_number, validator_->sample_count());
    if (absl::Status status = CheckLineLength(row, "row"); !status.ok()) return status;
    engine::ImuSample& sample = run_.samples.emplace_back();
    if (absl::Status status = ReadRow(row, sample); !status.ok()) return status;
    return validator_->Add(sample);
  }

  absl::Status FinishArrived() { return validator_->Finish(); }
  engine::BenchRun& run() { return run_; }

  absl::StatusOr<engine::BenchRun> Parse() {
    if (absl::Status status = ParseHead(); !status.ok()) return status;
    if (absl::Status status = ReadRows(*validator_); !status.ok()) return status;
    if (absl::Status status = validator_->Finish(); !status.ok()) return status;
    return std::move(run_);
  }

 private:
  absl::Status Refuse(std::string_view line, const char* at, std::string_view field,
                      std::string_view detail) const {
    return Refusal(locator_.At(lines_.number(), CharacterColumn(line, at), field), detail);
  }

  // Version 2's `segment_starts` (a free key to the metadata rules) becomes
  // the run's segments; in version 1 it is refused, not kept as free text.
  absl::Status TakeSegmentStarts() {
    auto& extra = run_.metadata.extra;
    for (std::size_t i = 0; i < extra.size(); ++i) {
      if (extra[i].first != kSegmentStartsKey) continue;
      const InputLocation where = locator_.OfMetadata(MetadataField::kExtra, i);
      if (run_.metadata.format != kFormatV2) {
        return Refusal(where, absl::StrFormat("segments need format '%s'", kFormatV2));
      }
      auto starts = ParseSegmentStarts(extra[i].second);
      if (!starts.ok()) return Refusal(where, std::string(starts.status().message()));
      run_.metadata.segment_starts = *std::move(starts);
      const std::string detail = CheckSegmentStarts(run_.metadata, std::numeric_limits<std::size_t>::max());
      if (!detail.empty()) return Refusal(where, detail);
      extra.erase(extra.begin() + static_cast<std::ptrdiff_t>(i));
      locator_.RemoveExtraPlace(i);
      return absl::OkStatus();
    }
    return absl::OkStatus();
  }

  // Reads `# key: value` lines up to the first other non-blank line, the header.
  absl::Status ReadMetadata(std::optional<std::string_view>& header) {
    std::string_view line;
    while (lines_.Next(line)) {
      if (absl::Status status = CheckLineLength(line, line.starts_with('#') ? "metadata" : "header");
          !status.ok()) {
        return status;
      }
      if (IsBlank(line)) continue;
      if (!line.starts_with('#')) {
        header = line;
        return absl::OkStatus();
      }
      if (absl::Status status = ReadMetadataLine(line); !status.ok()) return status;
    }
    return absl::OkStatus();
  }

  // Every line is bounded before it is looked into: a line-length bomb is
  // refused at its first byte past the limit.
  absl::Status CheckLineLength(std::string_view line, std::string_view field) const {
    if (line.size() <= kMaxLineBytes) return absl::OkStatus();
    return Refuse(line, line.data() + kMaxLineBytes, field,
                  absl::StrFormat("line of %d bytes is longer than %d bytes", line.size(), kMaxLineBytes));
  }

  absl::Status ReadMetadataLine(std::string_view line) {
    const char* const key_at = Trim(line.substr(1)).data();
    const auto key_begin = static_cast<std::size_t>(key_at - line.data());
    const std::size_t colon = line.find(':', key_begin);
    if (colon == line.npos) return Refuse(line, key_at, "metadata", "expected '# key: value'");
    const std::string_view key = Trim(line.substr(key_begin, colon - key_begin));
    if (key.size() > kMaxMetadataKeyBytes) {
      return Refuse(line, key_at, "metadata",
                    absl::StrFormat("key of %d bytes is longer than %d bytes", key.size(), kMaxMetadataKeyBytes));
    }
    if (!internal::IsMetadataKey(key)) {
      return Refuse(line, key_at, "metadata",
                    absl::StrFormat("expected '# key: value' with a lower-case ASCII key "
                                    "(a-z, 0-9, _), got '%s'",
                                    key));
    }
    if (const auto [seen, added] = seen_keys_.emplace(key, lines_.number()); !added) {
      return Refuse(line, key_at, key, absl::StrFormat("duplicate metadata key (first at line %d)", seen->second));
    }

    const std::string_view raw_value = line.substr(colon + 1);
    // Lines end at "\n" or "\r\n"; a control character inside one (a lone
    // carriage return) would not survive being written back.
    const auto control = std::find_if(raw_value.begin(), raw_value.end(), [](char c) {
      return (static_cast<unsigned char>(c) < 0x20 && c != '\t') || c == 0x7f;
    });
    if (control != raw_value.end()) {
      return Refuse(line, &*control, key,
                    absl::StrFormat("control character U+%04X in the value", static_cast<unsigned char>(*control)));
    }
    const std::string_view value = Trim(raw_value);
    if (value.size() > kMaxMetadataValueBytes) {
      return Refuse(line, value.data() + kMaxMetadataValueBytes, key,
                    absl::StrFormat("value of %d bytes is longer than %d bytes", value.size(),
                                    kMaxMetadataValueBytes));
    }
    if (const auto bad = FindInvalidUtf8(value)) {
      return Refuse(line, value.data() + *bad, key,
                    absl::StrFormat("byte 0x%02X is not UTF-8 text; metadata values are UTF-8",
                                    static_cast<unsigned char>(value[*bad])));
    }
    const char* const value_at = value.empty() ? raw_value.data() : value.data();
    const CsvLocator::Place value_place{lines_.number(), CharacterColumn(line, value_at)};

    const std::optional<MetadataField> field = SpecField(key);
    if (!field.has_value()) {
      if (std::string detail = internal::CheckReferenceKey(key, value); !detail.empty()) {
        return Refuse(line, value_at, key, detail);
      }
      // segment_starts is no free key once read (TakeSegmentStarts).
      if (run_.metadata.extra.size() >= kMaxFreeMetadataKeys + (key == kSegmentStartsKey ? 1 : 0)) {
        return Refuse(line, key_at, key,
                      absl::StrFormat("more than %d free metadata keys; a run holds at most %d",
                                      kMaxFreeMetadataKeys, kMaxFreeMetadataKeys));
      }
      run_.metadata.extra.emplace_back(key, value);
      locator_.AddExtraPlace(key, {lines_.number(), CharacterColumn(line, key_at)});
      return absl::OkStatus();
    }
    locator_.SetMetadataPlace(*field, value_place);
    const NumberParse outcome = StoreMetadata(*field, value);
    if (outcome != NumberParse::kOk) {
      return Refuse(line, value_at, key, internal::DescribeNumberParse(outcome, value));
    }
    // A file of another format may follow another grammar: say so before
    // reading further rather than report its lines as errors of this one.
    if (*field == MetadataField::kFormat) {
      if (std::string detail = internal::CheckFormat(value); !detail.empty()) {
        return Refuse(line, value_at, key, detail);
      }
    }
    return absl::OkStatus();
  }

  static std::optional<MetadataField> SpecField(std::string_view key) {
    for (std::size_t i = 0; i < kSpecMetadataFieldCount; ++i) {
      const auto field = static_cast<MetadataField>(i);
      if (MetadataKey(field) == key) return field;
    }
    return std::nullopt;
  }

  NumberParse StoreMetadata(MetadataField field, std::string_view value) {
    engine::BenchRunMetadata& metadata = run_.metadata;
    engine::Datasheet& sheet = metadata.datasheet;
    const auto store_optional = [value](std::optional<double>& target) {
      double number = 0.0;
      const NumberParse outcome = internal::ParseDouble(value, number);
      if (outcome == NumberParse::kOk) target = number;
      return outcome;
    };
    switch (field) {
      case MetadataField::kFormat:
        metadata.format = value;
        break;
      case MetadataField::kUnitSerial:
        metadata.unit_serial = value;
        break;
      case MetadataField::kUnitType:
        metadata.unit_type = value;
        break;
      case MetadataField::kSiteLatitude:
        return internal::ParseDegreesAsRadians(value, metadata.site.latitude_rad);
      case MetadataField::kSiteLongitude:
        return internal::ParseDegreesAsRadians(value, metadata.site.longitude_rad);
      case MetadataField::kSiteHeight:
        return internal::ParseDouble(value, metadata.site.height_m);
      case MetadataField::kGyroArw:
        return store_optional(sheet.gyro_arw_rad_rts);
      case MetadataField::kGyroBiasSigma:
        return store_optional(sheet.gyro_bias_sigma_rad_s);
      case MetadataField::kGyroBiasTau:
        return store_optional(sheet.gyro_bias_tau_s);
      case MetadataField::kAccVrw:
        return store_optional(sheet.acc_vrw_mps_rts);
      case MetadataField::kAccBiasSigma:
        return store_optional(sheet.acc_bias_sigma_mps2);
      case MetadataField::kAccBiasTau:
        return store_optional(sheet.acc_bias_tau_s);
      case MetadataField::kExtra:
        break;
    }
    return NumberParse::kOk;
  }

  // Missing keys are reported at the header line (where the metadata ends) or,
  // without a header, at the line after the last.
  absl::Status CheckRequiredKeys(bool header_found) const {
    const int line = header_found ? lines_.number() : lines_.number() + 1;
    for (const MetadataField field : kRequiredKeys) {
      if (!locator_.HasMetadata(field)) {
        return Refusal(locator_.At(line, 0, MetadataKey(field)), "missing required metadata key");
      }
    }
    return absl::OkStatus();
  }

  absl::Status ReadHeader(std::string_view line) {
    std::size_t begin = 0;
    while (true) {
      const std::size_t comma = line.find(',', begin);
      const std::string_view name = Trim(line.substr(begin, comma - begin));
      const char* const name_at = name.empty() ? line.data() + begin : name.data();
      if (std::find(column_names_.begin(), column_names_.end(), name) != column_names_.end()) {
        return Refuse(line, name_at, name, "duplicate column");
      }
      std::optional<SampleField> field;
      for (const SampleField candidate : internal::kAllSampleFields) {
        if (ColumnName(candidate) == name) field = candidate;
      }
      if (field.has_value())
        locator_.SetHeaderColumn(*field, static_cast<int>(column_names_.size()));
      column_names_.push_back(name);
      column_fields_.push_back(field);
      if (comma == line.npos) break;
      begin = comma + 1;
    }
    for (const SampleField field : internal::FieldsOf(/*has_temperature=*/false)) {
      if (!locator_.HasColumn(field)) {
        return Refusal(locator_.At(lines_.number(), 0, ColumnName(field)),
                       "missing required column");
      }
    }
    run_.has_temperature = locator_.HasColumn(SampleField::kTemp);
    return absl::OkStatus();
  }

  absl::Status ReadRows(BenchRunValidator& validator) {
    locator_.SetData(lines_.rest(), lines_.number() + 1);
    // Rows are lines: reserving by the line count leaves the vectors one
    // allocation each for the whole run.
    const auto row_bound =
        static_cast<std::size_t>(std::count(lines_.rest().begin(), lines_.rest().end(), '\n')) + 1;
    run_.samples.reserve(row_bound);
    validator.Reserve(row_bound);

    std::string_view line;
    while (lines_.Next(line)) {
      if (absl::Status status = CheckLineLength(line, "row"); !status.ok()) return status;
      if (IsBlank(line)) {
        if (IsBlank(lines_.rest())) break;  // blank lines at the end
        return Refuse(line, line.data(), "row",
                      absl::StrFormat("empty row, expected %d fields", column_fields_.size()));
      }
      engine::ImuSample& sample = run_.samples.emplace_back();
      if (absl::Status status = ReadRow(line, sample); !status.ok()) return status;
      if (absl::Status status = validator.Add(sample); !status.ok()) return status;
    }
    return absl::OkStatus();
  }

  absl::Status ReadRow(std::string_view line, engine::ImuSample& sample) const {
    const std::size_t column_count = column_fields_.size();
    std::size_t begin = 0;
    for (std::size_t k = 0; k < column_count; ++k) {
      const std::size_t comma = line.find(',', begin);
      if (const std::optional<SampleField> field = column_fields_[k]; field.has_value()) {
        const std::string_view text = Trim(line.substr(begin, comma - begin));
        const NumberParse outcome = internal::ParseDouble(text, internal::ValueOf(sample, *field));
        if (outcome != NumberParse::kOk) {
          const char* const text_at = text.empty() ? line.data() + begin : text.data();
          return Refuse(line, text_at, ColumnName(*field),
                        internal::DescribeNumberParse(outcome, text));
        }
      }
      if (comma == line.npos) {
        if (k + 1 == column_count) return absl::OkStatus();
        return Refuse(line, line.data() + line.size(), column_names_[k + 1],
                      absl::StrFormat("row has %d fields, expected %d", k + 1, column_count));
      }
      begin = comma + 1;
    }
    const auto extra_commas =
        std::count(line.begin() + static_cast<std::ptrdiff_t>(begin), line.end(), ',');
    return Refuse(
        line, line.data() + begin, "row",
        absl::StrFormat("row has %d fields, expected %d",
                        column_count + 1 + static_cast<std::size_t>(extra_commas), column_count));
  }

  LineReader lines_;
  CsvLocator locator_;
  engine::BenchRun run_;
  std::optional<BenchRunValidator> validator_;  // once the head is read
  std::unordered_map<std::string_view, int> seen_keys_;     // metadata key, its line
  std::vector<std::string_view> column_names_;               // header, in order
  std::vector<std::optional<SampleField>>
      column_fields_;  // nullopt: a column the spec does not name
};

}  // namespace

struct BenchRunLineStream::Reader {
  Reader(std::string_view head, std::string_view source) : parser(head, source) {}
  Parser parser;
};

BenchRunLineStream::BenchRunLineStream(std::string source_name) : source_(std::move(source_name)) {}
BenchRunLineStream::~BenchRunLineStream() = default;

absl::Status BenchRunLineStream::AddLine(std::string_view line) {
  ++line_number_;
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  if (reader_ != nullptr) {
    if (IsBlank(line)) return absl::OkStatus();  // the end may follow; rows after it are still checked
    return reader_->parser.ReadArrivedRow(line, line_number_);
  }
  // The head is kept until the header arrives: bound it by its lines' length
  // and, at one key more than a run may hold, read it for the precise refusal.
  if (line.size() > kMaxLineBytes) {
    return Refusal({.source = source_,
                    .line = line_number_,
                    .column = CharacterColumn(line, line.data() + kMaxLineBytes),
                    .field = line.starts_with('#') ? "metadata" : "header"},
                   absl::StrFormat("line of %d bytes is longer than %d bytes", line.size(), kMaxLineBytes));
  }
  head_.append(line);
  head_.push_back('\n');
  if (++head_lines_ > kMaxFreeMetadataKeys + kSpecMetadataFieldCount + kMaxHeadBlankLines) {
    if (absl::Status status = ParseBenchRun(head_, source_).status(); !status.ok()) return status;
    return Refusal({.source = source_, .line = line_number_, .field = "metadata"},
                   absl::StrFormat("more than %d lines before the header", head_lines_ - 1));
  }
  const std::string_view text = line_number_ == 1 && line.starts_with(kUtf8ByteOrderMark)
                                    ? line.substr(kUtf8ByteOrderMark.size())
                                    : line;
  if (IsBlank(text) || text.starts_with('#')) return absl::OkStatus();
  // The header: the head is complete, and read once.
  reader_ = std::make_unique<Reader>(head_, source_);
  if (absl::Status status = reader_->parser.ParseHead(); !status.ok()) {
    reader_.reset();
    return status;
  }
  return absl::OkStatus();
}

const engine::BenchRun& BenchRunLineStream::run() const {
  static const engine::BenchRun kNone;
  return reader_ != nullptr ? reader_->parser.run() : kNone;
}

std::vector<engine::ImuSample> BenchRunLineStream::TakeSamples() {
  if (reader_ == nullptr) return {};
  std::vector<engine::ImuSample> taken;
  taken.swap(reader_->parser.run().samples);
  return taken;
}

absl::Status BenchRunLineStream::Finish() {
  // Without a header the whole text is the head: its refusal is the reader's.
  if (reader_ == nullptr) return ParseBenchRun(head_, source_).status();
  return reader_->parser.FinishArrived();
}

absl::StatusOr<engine::BenchRun> ParseBenchRun(std::string_view text,
                                               std::string_view source_name) {
  return Parser(text, source_name).Parse();
}

absl::StatusOr<engine::BenchRun> ReadBenchRunFile(const std::filesystem::path& path) {
  const std::string name = path.string();
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(name.c_str(), "rb"),
                                                             &std::fclose);
  if (file == nullptr) return absl::ErrnoToStatus(errno, name + ": cannot open");
  std::string text;
  std::error_code size_error;
  const std::uintmax_t size = std::filesystem::file_size(path, size_error);
  if (!size_error) text.reserve(size);
  char buffer[1 << 16];
  std::size_t read = 0;
  while ((read = std::fread(buffer, 1, sizeof buffer, file.get())) > 0) text.append(buffer, read);
  if (std::ferror(file.get())) return absl::ErrnoToStatus(errno, name + ": cannot read");
  return ParseBenchRun(text, name);
}

}  // namespace insdiag::benchrun
