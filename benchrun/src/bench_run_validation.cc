#include "insdiag/benchrun/bench_run_validation.h"

#include <absl/strings/cord.h>
#include <absl/strings/numbers.h>
#include <absl/strings/str_format.h>

#include <algorithm>
#include <limits>
#include <array>
#include <charconv>
#include <cmath>
#include <numbers>
#include <unordered_set>

#include "insdiag/benchrun/text_rules.h"
#include "insdiag/engine/nav/wgs84.h"
#include "metadata_rules.h"
#include "number_text.h"
#include "sample_fields.h"

namespace insdiag::benchrun {
namespace {

using internal::IsMetadataKey;
using internal::ShortestText;

constexpr std::array<std::string_view, kSampleFieldCount> kColumnNames = {
    "t",     "gyro_x",   "gyro_y",    "gyro_z",  "acc_x", "acc_y",
    "acc_z", "ref_roll", "ref_pitch", "ref_yaw", "temp",
};

constexpr std::array<std::string_view, kSpecMetadataFieldCount> kMetadataKeys = {
    "format",         "unit_serial",  "unit_type",       "site_latitude_deg", "site_longitude_deg",
    "site_height_m",  "gyro_arw",     "gyro_bias_sigma", "gyro_bias_tau",     "acc_vrw",
    "acc_bias_sigma", "acc_bias_tau",
};

// Paths into engine::BenchRunMetadata, in MetadataField order.
constexpr std::array<std::string_view, kSpecMetadataFieldCount> kMetadataPaths = {
    "metadata.format",
    "metadata.unit_serial",
    "metadata.unit_type",
    "metadata.site.latitude_rad",
    "metadata.site.longitude_rad",
    "metadata.site.height_m",
    "metadata.datasheet.gyro_arw_rad_rts",
    "metadata.datasheet.gyro_bias_sigma_rad_s",
    "metadata.datasheet.gyro_bias_tau_s",
    "metadata.datasheet.acc_vrw_mps_rts",
    "metadata.datasheet.acc_bias_sigma_mps2",
    "metadata.datasheet.acc_bias_tau_s",
};

constexpr double kRadiansPerDegree = std::numbers::pi / 180.0;

bool IsGyro(SampleField field) {
  return field == SampleField::kGyroX || field == SampleField::kGyroY ||
         field == SampleField::kGyroZ;
}

bool IsSpecificForce(SampleField field) {
  return field == SampleField::kAccX || field == SampleField::kAccY || field == SampleField::kAccZ;
}

bool IsSpecMetadataKey(std::string_view key) {
  return std::find(kMetadataKeys.begin(), kMetadataKeys.end(), key) != kMetadataKeys.end();
}

std::string NotFinite(double value) { return ShortestText(value) + " is not a finite number"; }

// The refusal of a per-axis range: the limit and, where dividing by a unit
// factor brings the value within it, the unit the file is most likely in.
std::string BeyondLimit(double value, double limit, std::string_view unit, double likely_unit_in_si,
                        std::string_view likely_unit) {
  const std::string value_text = ShortestText(value);
  const std::string limit_text = ShortestText(limit);
  if (std::abs(value) * likely_unit_in_si <= limit) {
    return absl::StrFormat("%s %s is beyond ±%s %s: looks like %s, expected %s", value_text, unit,
                           limit_text, unit, likely_unit, unit);
  }
  return absl::StrFormat("%s %s is beyond ±%s %s (wrong units?)", value_text, unit, limit_text,
                         unit);
}

// The per-sample rules of one value; empty when it passes.
std::string CheckSampleValue(SampleField field, double value) {
  if (!std::isfinite(value)) return NotFinite(value);
  if (IsGyro(field) && std::abs(value) > kMaxGyroRateRadS) {
    return BeyondLimit(value, kMaxGyroRateRadS, "rad/s", kRadiansPerDegree, "deg/s");
  }
  if (IsSpecificForce(field) && std::abs(value) > kMaxSpecificForceMps2) {
    return absl::StrFormat("%s m/s² is beyond ±%s m/s² (wrong units?)", ShortestText(value),
                           ShortestText(kMaxSpecificForceMps2));
  }
  return {};
}

// Why a metadata value breaks the text limits; empty when it keeps them.
std::string CheckMetadataText(std::string_view value, std::size_t max_bytes = kMaxMetadataValueBytes) {
  if (value.size() > max_bytes) {
    return absl::StrFormat("value of %d bytes is longer than %d bytes", value.size(), max_bytes);
  }
  if (const auto bad = FindInvalidUtf8(value)) {
    return absl::StrFormat("byte 0x%02X at byte %d of the value is not UTF-8 text", static_cast<unsigned char>(value[*bad]),
                           *bad + 1);
  }
  return {};
}

// Free metadata must survive a trip through the text format, and stay within
// the limits. One pass and a hash set: linear in the number of keys.
template <typename Refuse>
absl::Status CheckFreeMetadata(const std::vector<std::pair<std::string, std::string>>& extra, const Refuse& refuse) {
  if (extra.size() > kMaxFreeMetadataKeys) {
    return refuse(MetadataField::kExtra,
                  absl::StrFormat("%d free metadata keys; a run holds at most %d", extra.size(), kMaxFreeMetadataKeys),
                  kMaxFreeMetadataKeys);
  }
  std::unordered_set<std::string_view> seen;
  seen.reserve(extra.size());
  for (std::size_t i = 0; i < extra.size(); ++i) {
    const auto& [key, value] = extra[i];
    if (key.size() > kMaxMetadataKeyBytes) {
      return refuse(MetadataField::kExtra,
                    absl::StrFormat("key of %d bytes is longer than %d bytes", key.size(), kMaxMetadataKeyBytes), i);
    }
    if (!IsMetadataKey(key)) {
      return refuse(MetadataField::kExtra,
                    absl::StrFormat("key '%s' is not lower-case ASCII (a-z, 0-9, _)", key), i);
    }
    if (IsSpecMetadataKey(key)) {
      return refuse(MetadataField::kExtra,
                    absl::StrFormat("key '%s' is a spec key, not free metadata", key), i);
    }
    if (!seen.insert(key).second) {
      return refuse(MetadataField::kExtra, absl::StrFormat("duplicate key '%s'", key), i);
    }
    if (std::string detail = CheckMetadataText(value); !detail.empty()) {
      return refuse(MetadataField::kExtra, absl::StrFormat("'%s': %s", key, detail), i);
    }
    if (value.find_first_of("\r\n") != std::string::npos) {
      return refuse(MetadataField::kExtra, absl::StrFormat("value of '%s' spans lines", key), i);
    }
    if (std::string detail = internal::CheckReferenceKey(key, value); !detail.empty()) {
      return refuse(MetadataField::kExtra, detail, i);
    }
  }
  return absl::OkStatus();
}

absl::Status CheckMetadata(const engine::BenchRunMetadata& metadata, const InputLocator& locator) {
  const auto refuse = [&](MetadataField field, std::string_view detail,
                          std::size_t extra_index = 0) {
    return Refusal(locator.OfMetadata(field, extra_index), detail);
  };
  if (std::string detail = internal::CheckFormat(metadata.format); !detail.empty()) {
    return refuse(MetadataField::kFormat, detail);
  }
  if (std::string detail = CheckUnitSerial(metadata.unit_serial); !detail.empty()) {
    return refuse(MetadataField::kUnitSerial, detail);
  }
  if (std::string detail = CheckMetadataText(metadata.unit_type, kMaxUnitTypeBytes); !detail.empty()) {
    return refuse(MetadataField::kUnitType, detail);
  }

  const engine::Site& site = metadata.site;
  const engine::Datasheet& sheet = metadata.datasheet;
  const std::array<std::pair<MetadataField, std::optional<double>>, 9> numbers = {{
      {MetadataField::kSiteLatitude, site.latitude_rad},
      {MetadataField::kSiteLongitude, site.longitude_rad},
      {MetadataField::kSiteHeight, site.height_m},
      {MetadataField::kGyroArw, sheet.gyro_arw_rad_rts},
      {MetadataField::kGyroBiasSigma, sheet.gyro_bias_sigma_rad_s},
      {MetadataField::kGyroBiasTau, sheet.gyro_bias_tau_s},
      {MetadataField::kAccVrw, sheet.acc_vrw_mps_rts},
      {MetadataField::kAccBiasSigma, sheet.acc_bias_sigma_mps2},
      {MetadataField::kAccBiasTau, sheet.acc_bias_tau_s},
  }};
  for (const auto& [field, value] : numbers) {
    if (value.has_value() && !std::isfinite(*value)) {
      return refuse(field, NotFinite(*value));
    }
  }
  // Compared in radians: 90° read from the text is exactly π/2 rounded.
  if (std::abs(site.latitude_rad) > kMaxLatitudeDeg * kRadiansPerDegree) {
    return refuse(MetadataField::kSiteLatitude,
                  absl::StrFormat("latitude %s° is outside ±%s°",
                                  ShortestText(internal::DegreesFromRadians(site.latitude_rad)),
                                  ShortestText(kMaxLatitudeDeg)));
  }

  return CheckFreeMetadata(metadata.extra, refuse);
  return absl::OkStatus();
}

}  // namespace

std::string_view ColumnName(SampleField field) {
  return kColumnNames[static_cast<std::size_t>(field)];
}

std::string_view MetadataKey(MetadataField field) {
  const auto index = static_cast<std::size_t>(field);
  return index < kMetadataKeys.size() ? kMetadataKeys[index] : std::string_view();
}

namespace internal {

bool IsMetadataKey(std::string_view key) {
  if (key.empty() || key.front() < 'a' || key.front() > 'z') return false;
  return std::all_of(key.begin(), key.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
  });
}

std::string CheckReferenceKey(std::string_view key, std::string_view value) {
  if (key == engine::kReferenceAttitudeReadoutKey) {
    if (value == engine::kAttitudeReadByEncoders || value == engine::kAttitudeNotRead) return {};
    return absl::StrFormat("expected '%s' or '%s', got '%s'", engine::kAttitudeReadByEncoders,
                           engine::kAttitudeNotRead, value);
  }
  const bool heading = key == engine::kReferenceHeadingSigmaKey;
  if (!heading && key != engine::kReferenceLevelSigmaKey) return {};
  if (heading && value == engine::kHeadingNotSurveyed) return {};
  double sigma_rad = 0.0;
  if (absl::SimpleAtod(absl::string_view(value.data(), value.size()), &sigma_rad) && std::isfinite(sigma_rad) && sigma_rad > 0.0) return {};
  return absl::StrFormat("expected a positive 1σ in radians%s, got '%s'",
                         heading ? absl::StrFormat(" or '%s'", engine::kHeadingNotSurveyed) : "", value);
}

std::string CheckFormat(std::string_view format) {
  if (format.empty()) return "is missing";
  if (format == kFormatV1 || format == kFormatV2) return {};
  return absl::StrFormat("unknown format '%s', expected '%s' or '%s'", format, kFormatV1, kFormatV2);
}

}  // namespace internal

// ---------------------------------------------------------------------------
// Locations

absl::Status Refusal(const InputLocation& where, std::string_view detail) {
  // A source is a name the caller gave (a path may hold a tab): kept as it
  // is unless it is not UTF-8.
  std::string message = FindInvalidUtf8(where.source) ? Utf8Printable(where.source) : where.source;
  if (where.line > 0) message += absl::StrFormat(":%d", where.line);
  if (where.line > 0 && where.column > 0) message += absl::StrFormat(":%d", where.column);
  // Details quote the input: hostile bytes are escaped so that the message is
  // UTF-8 on one line (it travels in protobuf strings and JSON).
  const std::string field = Utf8Printable(where.field);
  message += absl::StrFormat(": %s: %s", field, Utf8Printable(detail));
  absl::Status status = absl::InvalidArgumentError(message);
  // The source goes last so that it may hold tabs; fields are names without tabs.
  status.SetPayload(kInputLocationTypeUrl,
                    absl::Cord(absl::StrFormat("%d\t%d\t%s\t%s", where.line, where.column,
                                               field, where.source)));
  return status;
}

std::optional<InputLocation> LocationOf(const absl::Status& status) {
  const absl::optional<absl::Cord> payload = status.GetPayload(kInputLocationTypeUrl);
  if (!payload.has_value()) return std::nullopt;
  const std::string encoded(*payload);
  std::string_view rest = encoded;
  const auto take = [&rest]() -> std::optional<std::string_view> {
    const std::size_t tab = rest.find('\t');
    if (tab == std::string_view::npos) return std::nullopt;
    std::string_view part = rest.substr(0, tab);
    rest.remove_prefix(tab + 1);
    return part;
  };
  const auto to_int = [](std::string_view text, int& value) {
    const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    return ec == std::errc() && ptr == text.data() + text.size();
  };
  const auto line = take();
  const auto column = take();
  const auto field = take();
  InputLocation location;
  if (!line || !column || !field || !to_int(*line, location.line) ||
      !to_int(*column, location.column)) {
    return std::nullopt;
  }
  location.field = std::string(*field);
  location.source = std::string(rest);
  return location;
}

InputLocation FieldPathLocator::OfSample(std::size_t sample_index, SampleField field) const {
  return {.source = source_name_,
          .field = absl::StrFormat("samples[%d].%s", sample_index, ColumnName(field))};
}

InputLocation FieldPathLocator::OfMetadata(MetadataField field, std::size_t extra_index) const {
  const auto index = static_cast<std::size_t>(field);
  return {.source = source_name_,
          .field = index < kMetadataPaths.size()
                       ? std::string(kMetadataPaths[index])
                       : absl::StrFormat("metadata.extra[%d]", extra_index)};
}

InputLocation FieldPathLocator::OfSampleList() const {
  return {.source = source_name_, .field = "samples"};
}

// ---------------------------------------------------------------------------
// Validator

absl::StatusOr<BenchRunValidator> BenchRunValidator::Create(
    const engine::BenchRunMetadata& metadata, bool has_temperature, const InputLocator& locator) {
  if (absl::Status status = CheckMetadata(metadata, locator); !status.ok()) return status;
  if (std::string detail = CheckSegmentStarts(metadata, std::numeric_limits<std::size_t>::max()); !detail.empty()) {
    InputLocation where = locator.OfMetadata(MetadataField::kFormat, 0);
    where.field = kSegmentStartsKey;
    return Refusal(where, detail);
  }
  const double gravity =
      engine::wgs84::NormalGravityMps2(metadata.site.latitude_rad, metadata.site.height_m);
  BenchRunValidator validator(gravity, has_temperature, locator);
  validator.segment_starts_ = metadata.segment_starts;
  return validator;
}

void BenchRunValidator::Reserve(std::size_t sample_count) {
  intervals_s_.reserve(sample_count > 0 ? sample_count - 1 : 0);
}

absl::Status BenchRunValidator::Add(const engine::ImuSample& sample) {
  const std::size_t index = sample_count_;
  for (const SampleField field : internal::FieldsOf(has_temperature_)) {
    if (std::string detail = CheckSampleValue(field, internal::ValueOf(sample, field));
        !detail.empty()) {
      return Refusal(locator_->OfSample(index, field), detail);
    }
  }

  if (index == 0) {
    first_t_s_ = sample.t_s;
  } else {
    const double interval = sample.t_s - previous_t_s_;
    if (!(interval > 0.0)) {
      return Refusal(locator_->OfSample(index, SampleField::kT),
                     absl::StrFormat("t = %s s does not increase (previous sample: %s s)",
                                     ShortestText(sample.t_s), ShortestText(previous_t_s_)));
    }
    intervals_s_.push_back(interval);
    if (record_intervals_s_.empty() || interval > record_intervals_s_.back().second) {
      record_intervals_s_.emplace_back(index, interval);
    }
  }
  previous_t_s_ = sample.t_s;
  ++sample_count_;

  if (!window_checked_) {
    if (sample.t_s - first_t_s_ < kGravityWindowS) {
      window_force_sum_mps2_ += sample.acc_mps2.norm();
      ++window_sample_count_;
    } else {
      window_checked_ = true;
      return CheckGravityWindow();
    }
  }
  return absl::OkStatus();
}

absl::Status BenchRunValidator::Add(std::span<const engine::ImuSample> samples) {
  for (const engine::ImuSample& sample : samples) {
    if (absl::Status status = Add(sample); !status.ok()) return status;
  }
  return absl::OkStatus();
}

absl::Status BenchRunValidator::CheckGravityWindow() const {
  const double mean = window_force_sum_mps2_ / static_cast<double>(window_sample_count_);
  if (std::abs(mean - normal_gravity_mps2_) <= kGravityRelativeTolerance * normal_gravity_mps2_) {
    return absl::OkStatus();
  }
  std::string detail = absl::StrFormat(
      "mean specific-force magnitude over the first %s s (%d samples) is %s m/s², local normal "
      "gravity is %s m/s² (tolerance ±%s%%)",
      ShortestText(kGravityWindowS), window_sample_count_, ShortestText(mean),
      ShortestText(normal_gravity_mps2_), ShortestText(100.0 * kGravityRelativeTolerance));
  // A file in g reads about 1 where one in m/s² reads g, i.e. mean / g ≈ 1 / g;
  // the same relative tolerance applies around 1.
  if (std::abs(mean - 1.0) <= kGravityRelativeTolerance) {
    detail += ": looks like units of g, expected m/s²";
  }
  return Refusal(locator_->OfSample(0, SampleField::kAccX), detail);
}

absl::Status BenchRunValidator::Finish() {
  if (sample_count_ == 0) return Refusal(locator_->OfSampleList(), "the run has no samples");
  if (!segment_starts_.empty() && segment_starts_.back() >= sample_count_) {
    InputLocation where = locator_->OfSampleList();
    where.field = kSegmentStartsKey;
    return Refusal(where, absl::StrFormat("segment start %d is past the last sample (%d samples)",
                                          segment_starts_.back(), sample_count_));
  }
  if (!window_checked_) {
    window_checked_ = true;
    if (absl::Status status = CheckGravityWindow(); !status.ok()) return status;
  }
  if (intervals_s_.empty()) return absl::OkStatus();

  // Same definition as engine::BenchRun::NominalIntervalS (upper median).
  const auto middle = intervals_s_.begin() + static_cast<std::ptrdiff_t>(intervals_s_.size() / 2);
  std::nth_element(intervals_s_.begin(), middle, intervals_s_.end());
  const double nominal = *middle;
  const double limit = kMaxGapNominalIntervals * nominal;
  for (const auto& [index, interval] : record_intervals_s_) {
    if (interval > limit) {
      return Refusal(locator_->OfSample(index, SampleField::kT),
                     absl::StrFormat("gap of %s s since the previous sample is longer than %s "
                                     "nominal intervals (%s s, the median interval)",
                                     ShortestText(interval), ShortestText(kMaxGapNominalIntervals),
                                     ShortestText(nominal)));
    }
  }
  return absl::OkStatus();
}

std::string_view FormatOf(const engine::BenchRun& run) { return run.metadata.segment_starts.empty() ? kFormatV1 : kFormatV2; }

std::string CheckSegmentStarts(const engine::BenchRunMetadata& metadata, std::size_t sample_count) {
  if (metadata.segment_starts.empty()) return {};
  if (metadata.format != kFormatV2) {
    return absl::StrFormat("segments need format '%s' (this run says '%s')", kFormatV2, metadata.format);
  }
  std::size_t previous = 0;
  for (const std::size_t start : metadata.segment_starts) {
    if (start <= previous || start >= sample_count) {
      return absl::StrFormat("%d is not after %d and before the sample count %d: starts increase within the run",
                             start, previous, sample_count);
    }
    previous = start;
  }
  return {};
}

absl::StatusOr<std::vector<std::size_t>> ParseSegmentStarts(std::string_view text) {
  std::vector<std::size_t> starts;
  std::size_t begin = 0;
  while (begin <= text.size()) {
    std::size_t end = text.find(',', begin);
    if (end == std::string_view::npos) end = text.size();
    std::string_view item = text.substr(begin, end - begin);
    while (!item.empty() && item.front() == ' ') item.remove_prefix(1);
    while (!item.empty() && item.back() == ' ') item.remove_suffix(1);
    std::size_t value = 0;
    const auto [ptr, ec] = std::from_chars(item.data(), item.data() + item.size(), value);
    if (item.empty() || ec != std::errc() || ptr != item.data() + item.size()) {
      return absl::InvalidArgumentError(absl::StrFormat("'%s' is not a sample index", item));
    }
    starts.push_back(value);
    begin = end + 1;
  }
  return starts;
}

std::string SegmentStartsText(const std::vector<std::size_t>& starts) {
  std::string text;
  for (const std::size_t s : starts) {
    if (!text.empty()) text.push_back(',');
    text.append(std::to_string(s));
  }
  return text;
}

absl::Status ValidateBenchRun(const engine::BenchRun& run, std::string_view source_name) {
  const FieldPathLocator locator{std::string(source_name)};
  absl::StatusOr<BenchRunValidator> validator =
      BenchRunValidator::Create(run.metadata, run.has_temperature, locator);
  if (!validator.ok()) return validator.status();
  validator->Reserve(run.samples.size());
  if (absl::Status status = validator->Add(run.samples); !status.ok()) return status;
  return validator->Finish();
}

}  // namespace insdiag::benchrun
