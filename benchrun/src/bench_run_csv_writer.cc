#include <cerrno>
#include <charconv>
#include <cstdio>
#include <memory>
#include <optional>
#include <span>

#include "insdiag/benchrun/bench_run_csv.h"
#include "number_text.h"
#include "sample_fields.h"

namespace insdiag::benchrun {
namespace {

void AppendMetadataLine(std::string& out, std::string_view key, std::string_view value) {
  out.append("# ").append(key).append(": ").append(value).append("\n");
}

void AppendMetadata(std::string& out, MetadataField field, std::string_view value) {
  AppendMetadataLine(out, MetadataKey(field), value);
}

void AppendOptionalNumber(std::string& out, MetadataField field,
                          const std::optional<double>& value) {
  if (value.has_value()) AppendMetadata(out, field, internal::ShortestText(*value));
}

// Longest shortest-round-trip double text ("-2.2250738585072014e-308") plus a comma.
constexpr std::size_t kMaxNumberChars = 25;

void AppendRows(std::string& out, const engine::BenchRun& run) {
  const std::span<const SampleField> fields = internal::FieldsOf(run.has_temperature);
  char row[kSampleFieldCount * kMaxNumberChars + 1];
  for (const engine::ImuSample& sample : run.samples) {
    char* end = row;
    for (const SampleField field : fields) {
      if (end != row) *end++ = ',';
      end = std::to_chars(end, row + sizeof row, internal::ValueOf(sample, field)).ptr;
    }
    *end++ = '\n';
    out.append(row, end);
  }
}

}  // namespace

std::string FormatBenchRun(const engine::BenchRun& run) {
  const engine::BenchRunMetadata& metadata = run.metadata;
  const engine::Datasheet& sheet = metadata.datasheet;
  std::string out;
  out.reserve(1024 + run.samples.size() * 12 * kSampleFieldCount);

  // Version 1, or 2 for a run of segments, whatever the value says.
  AppendMetadata(out, MetadataField::kFormat, FormatOf(run));
  AppendMetadata(out, MetadataField::kUnitSerial, metadata.unit_serial);
  if (!metadata.unit_type.empty())
    AppendMetadata(out, MetadataField::kUnitType, metadata.unit_type);
  AppendMetadata(out, MetadataField::kSiteLatitude,
                 internal::DegreesText(metadata.site.latitude_rad));
  AppendMetadata(out, MetadataField::kSiteLongitude,
                 internal::DegreesText(metadata.site.longitude_rad));
  AppendMetadata(out, MetadataField::kSiteHeight, internal::ShortestText(metadata.site.height_m));
  AppendOptionalNumber(out, MetadataField::kGyroArw, sheet.gyro_arw_rad_rts);
  AppendOptionalNumber(out, MetadataField::kGyroBiasSigma, sheet.gyro_bias_sigma_rad_s);
  AppendOptionalNumber(out, MetadataField::kGyroBiasTau, sheet.gyro_bias_tau_s);
  AppendOptionalNumber(out, MetadataField::kAccVrw, sheet.acc_vrw_mps_rts);
  AppendOptionalNumber(out, MetadataField::kAccBiasSigma, sheet.acc_bias_sigma_mps2);
  AppendOptionalNumber(out, MetadataField::kAccBiasTau, sheet.acc_bias_tau_s);
  if (!run.metadata.segment_starts.empty()) AppendMetadataLine(out, kSegmentStartsKey, SegmentStartsText(run.metadata.segment_starts));
  for (const auto& [key, value] : metadata.extra) AppendMetadataLine(out, key, value);

  const char* separator = "";
  for (const SampleField field : internal::FieldsOf(run.has_temperature)) {
    out.append(separator).append(ColumnName(field));
    separator = ",";
  }
  out += '\n';
  AppendRows(out, run);
  return out;
}

absl::Status WriteBenchRunFile(const engine::BenchRun& run, const std::filesystem::path& path) {
  const std::string name = path.string();
  if (absl::Status status = ValidateBenchRun(run, name); !status.ok()) return status;
  const std::string text = FormatBenchRun(run);

  // Written beside the target and renamed over it, so that a reader never sees
  // half a file and a failed write leaves the target as it was.
  const std::string partial = name + ".partial";
  std::FILE* file = std::fopen(partial.c_str(), "wb");
  if (file == nullptr) return absl::ErrnoToStatus(errno, partial + ": cannot open");
  const bool written = std::fwrite(text.data(), 1, text.size(), file) == text.size();
  const int write_errno = errno;
  const bool closed = std::fclose(file) == 0;
  if (!written || !closed) {
    const int error = written ? errno : write_errno;
    std::remove(partial.c_str());
    return absl::ErrnoToStatus(error, partial + ": cannot write");
  }
  if (std::rename(partial.c_str(), name.c_str()) != 0) {
    const int error = errno;
    std::remove(partial.c_str());
    return absl::ErrnoToStatus(error, name + ": cannot replace");
  }
  return absl::OkStatus();
}

}  // namespace insdiag::benchrun
