// Value rules of a bench run, shared by every input path: the CSV reader
// (bench_run_csv.h) and typed uploads (gRPC), so that both refuse the same runs
// (spec: shared/spec/bench-run-format.md, "What the reader must refuse").
//
// Rules, in SI units as the run holds them:
//   metadata   format == "insdiag-bench-run/1"; unit_serial follows the
//              serial rule (text_rules.h); unit_type UTF-8;
//              site and datasheet values finite; |latitude| ≤ 90°;
//              free (extra) keys are lower-case ASCII, not a spec key, unique,
//              values UTF-8 on one line; the limits below
//   samples    every value finite (temp only when the run has temperature)
//              t_k > t_{k−1}
//              |gyro_i| ≤ 35 rad/s, |acc_i| ≤ 500 m/s²           (per axis)
//              |mean ‖f_k‖ − γ(φ, h)| ≤ 0.10 · γ(φ, h)           over the samples with
//                                                               t_k − t_0 < 1 s
//              t_k − t_{k−1} ≤ 5 · Δt_nominal,  Δt_nominal = median of t_k − t_{k−1}
//              at least one sample
// where γ is WGS-84 normal gravity at the site. Rates a factor 180/π too large
// are reported as "looks like deg/s", a mean specific force near 1 as "looks
// like units of g": these rules mostly catch files in the wrong units.
//
// A refusal is absl::InvalidArgumentError with the message
// "source:line:column: field: detail" (line and column left out when 0) and the
// structured InputLocation attached as a payload (see LocationOf).
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "insdiag/engine/bench_run.h"

namespace insdiag::benchrun {

inline constexpr std::string_view kFormatV1 = "insdiag-bench-run/1";
// Version 2: version 1 and the metadata key `segment_starts`, the first
// sample of each segment after the first of a multi-position test
// (docs/MULTI_POSITION.md). A run of one segment is written as version 1.
inline constexpr std::string_view kFormatV2 = "insdiag-bench-run/2";
inline constexpr std::string_view kSegmentStartsKey = "segment_starts";

// The format a run is written in: version 2 when it has segments.
std::string_view FormatOf(const engine::BenchRun& run);

// Checks a run's segment starts against its sample count and format:
// increasing, each within (0, sample count), and only in version 2. An empty
// string when they hold, else what is wrong. BenchRunValidator applies it.
std::string CheckSegmentStarts(const engine::BenchRunMetadata& metadata, std::size_t sample_count);

// Parses `segment_starts` ("3000,6000,9100"), or says why not.
absl::StatusOr<std::vector<std::size_t>> ParseSegmentStarts(std::string_view text);
std::string SegmentStartsText(const std::vector<std::size_t>& starts);

// Limits of the rules above, part of the format contract.
inline constexpr double kMaxGyroRateRadS = 35.0;
inline constexpr double kMaxSpecificForceMps2 = 500.0;
inline constexpr double kMaxLatitudeDeg = 90.0;
inline constexpr double kGravityWindowS = 1.0;             // "the first second"
inline constexpr double kGravityRelativeTolerance = 0.10;  // of local normal gravity
inline constexpr double kMaxGapNominalIntervals = 5.0;

// Size limits, checked before anything else is done with the text: no bench
// writes more than a few dozen free keys of a line each, and each limit is far
// above what a factory file holds (docs/API.md, "Limits"), while a run at the
// limits stays about 1 MiB of metadata, well within a gRPC message.
inline constexpr std::size_t kMaxFreeMetadataKeys = 256;
inline constexpr std::size_t kMaxMetadataKeyBytes = 64;
inline constexpr std::size_t kMaxMetadataValueBytes = 4096;
// A model name ("INS-2000"); listings carry it for every run.
inline constexpr std::size_t kMaxUnitTypeBytes = 128;
// Any line of the CSV text: a metadata line at the key and value limits fits.
inline constexpr std::size_t kMaxLineBytes = 8192;

// Where a refused input is wrong. line/column are 1-based and 0 when not
// applicable (e.g. a missing column names the header line and column 0; a gRPC
// upload names `field` as "samples[1234].gyro_x" and leaves line/column 0).
// column counts characters (UTF-8 code points), not bytes.
struct InputLocation {
  std::string source;
  int line = 0;
  int column = 0;
  std::string field;

  bool operator==(const InputLocation&) const = default;
};

// Type URL of the InputLocation payload. Encoding: "line\tcolumn\tfield\tsource".
// (A char array: Debian's abseil has its own absl::string_view, which a
// std::string_view does not convert to.)
inline constexpr char kInputLocationTypeUrl[] =
    "type.googleapis.com/insdiag.benchrun.InputLocation";

// The location a refusal carries, if the Status came from this library.
std::optional<InputLocation> LocationOf(const absl::Status& status);

// A refusal of the input at `where`: InvalidArgument, message
// "source:line:column: field: detail", location attached as payload.
absl::Status Refusal(const InputLocation& where, std::string_view detail);

// The values of a sample, in the spec's column order.
enum class SampleField {
  kT,
  kGyroX,
  kGyroY,
  kGyroZ,
  kAccX,
  kAccY,
  kAccZ,
  kRefRoll,
  kRefPitch,
  kRefYaw,
  kTemp,
};
inline constexpr std::size_t kSampleFieldCount = 11;

// The spec's column name ("gyro_x"), also used in field paths.
std::string_view ColumnName(SampleField field);

// The metadata the rules speak of, in the order the writer puts them.
enum class MetadataField {
  kFormat,
  kUnitSerial,
  kUnitType,
  kSiteLatitude,
  kSiteLongitude,
  kSiteHeight,
  kGyroArw,
  kGyroBiasSigma,
  kGyroBiasTau,
  kAccVrw,
  kAccBiasSigma,
  kAccBiasTau,
  kExtra,  // one of metadata.extra, by index
};
inline constexpr std::size_t kSpecMetadataFieldCount = 12;  // all but kExtra

// The spec's metadata key ("site_latitude_deg"); empty for kExtra.
std::string_view MetadataKey(MetadataField field);

// Maps the subject of a rule to a place in the input.
class InputLocator {
 public:
  virtual ~InputLocator() = default;
  virtual InputLocation OfSample(std::size_t sample_index, SampleField field) const = 0;
  // `extra_index` is meaningful for MetadataField::kExtra only.
  virtual InputLocation OfMetadata(MetadataField field, std::size_t extra_index) const = 0;
  // Where the samples start: names a run that has none.
  virtual InputLocation OfSampleList() const = 0;
};

// Names places as paths into the BenchRun value, line and column 0, as for a
// typed upload: "samples[12].gyro_x", "metadata.site.latitude_rad",
// "metadata.extra[2]", "samples".
class FieldPathLocator final : public InputLocator {
 public:
  explicit FieldPathLocator(std::string source_name) : source_name_(std::move(source_name)) {}
  InputLocation OfSample(std::size_t sample_index, SampleField field) const override;
  InputLocation OfMetadata(MetadataField field, std::size_t extra_index) const override;
  InputLocation OfSampleList() const override;

 private:
  std::string source_name_;
};

// Checks a run incrementally, as its samples arrive (whole or in chunks):
//
//   const FieldPathLocator locator("upload");
//   absl::StatusOr<BenchRunValidator> validator =
//       BenchRunValidator::Create(metadata, has_temperature, locator);
//   if (!validator.ok()) return validator.status();
//   for (each chunk) if (absl::Status s = validator->Add(chunk); !s.ok()) return s;
//   return validator->Finish();
//
// Create applies the metadata rules, Add the per-sample rules (finite, t order,
// ranges, gravity once the first second is complete), Finish the rules that
// need the whole run (gap rule, since the nominal interval is the median of all
// intervals; gravity of a run shorter than the window; at least one sample).
// A gap is named at the sample that ends it (field t), the gravity rule at the
// first sample's acc_x. The first violation is returned; do not feed the
// validator after one. Memory: 8 bytes per sample for the intervals.
class BenchRunValidator {
 public:
  // Refuses metadata that breaks a rule. `locator` must outlive the validator.
  static absl::StatusOr<BenchRunValidator> Create(const engine::BenchRunMetadata& metadata,
                                                  bool has_temperature,
                                                  const InputLocator& locator);
  // A temporary locator would dangle.
  static absl::StatusOr<BenchRunValidator> Create(const engine::BenchRunMetadata&, bool,
                                                  const InputLocator&&) = delete;

  // Reserves room for the intervals of `sample_count` samples.
  void Reserve(std::size_t sample_count);

  absl::Status Add(const engine::ImuSample& sample);
  absl::Status Add(std::span<const engine::ImuSample> samples);
  absl::Status Finish();

  std::size_t sample_count() const { return sample_count_; }

 private:
  BenchRunValidator(double normal_gravity_mps2, bool has_temperature, const InputLocator& locator)
      : normal_gravity_mps2_(normal_gravity_mps2),
        has_temperature_(has_temperature),
        locator_(&locator) {}

  absl::Status CheckGravityWindow() const;

  double normal_gravity_mps2_;
  bool has_temperature_;
  const InputLocator* locator_;

  std::size_t sample_count_ = 0;
  std::vector<std::size_t> segment_starts_;  // checked against the sample count by Finish
  double first_t_s_ = 0.0;
  double previous_t_s_ = 0.0;

  // Mean ‖f‖ over the first kGravityWindowS, checked once the window closes.
  double window_force_sum_mps2_ = 0.0;
  std::size_t window_sample_count_ = 0;
  bool window_checked_ = false;

  // t_k − t_{k−1} for k ≥ 1 (index k−1), for the median; and the intervals
  // longer than every earlier one, with their k: the first interval above the
  // gap limit is among them, so Finish finds it without keeping the order.
  std::vector<double> intervals_s_;
  std::vector<std::pair<std::size_t, double>> record_intervals_s_;
};

// Applies every rule to a complete run; places are named by field path
// (FieldPathLocator), e.g. "upload: samples[12].gyro_x: ...".
absl::Status ValidateBenchRun(const engine::BenchRun& run, std::string_view source_name);

}  // namespace insdiag::benchrun
