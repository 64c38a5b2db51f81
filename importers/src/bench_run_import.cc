#include "insdiag/importers/bench_run_import.h"

#include <absl/strings/str_format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include "insdiag/benchrun/bench_run_csv.h"
#include "insdiag/engine/nav/coarse_alignment.h"
#include "insdiag/engine/status_macros.h"
#include "insdiag/importers/import_recipe.h"
#include "insdiag/importers/presets.h"
#include "raw_records.h"

namespace insdiag::importers {
namespace {

using benchrun::InputLocation;
using benchrun::Refusal;
using internal::DecodedRecords;

// Over a window where the mean body rate exceeds this, the unit was turning
// (0.57°/s: above the bias of any navigation or tactical gyro and Earth's
// rate by two orders), so it cannot be levelled or gyro-compassed there.
constexpr double kStaticMeanRateLimitRadS = 0.01;

// Names the raw log's line (text) or record (binary) of a sample.
class RecordLocator final : public benchrun::InputLocator {
 public:
  RecordLocator(std::string source, const DecodedRecords& records, bool binary)
      : source_(std::move(source)), records_(records), binary_(binary) {}
  InputLocation OfSample(std::size_t i, benchrun::SampleField field) const override {
    const std::string name(benchrun::ColumnName(field));
    if (binary_) return {source_, 0, 0, absl::StrFormat("record %d: %s", records_.origin[i], name)};
    return {source_, static_cast<int>(records_.origin[i]), 0, name};
  }
  InputLocation OfMetadata(benchrun::MetadataField field, std::size_t) const override {
    return {"settings", 0, 0, std::string(benchrun::MetadataKey(field))};
  }
  InputLocation OfSampleList() const override { return {source_, 0, 0, "records"}; }

 private:
  std::string source_;
  const DecodedRecords& records_;
  bool binary_;
};

bool HasColumn(const ImportRecipe& recipe, ColumnTarget target) {
  return std::any_of(recipe.columns.begin(), recipe.columns.end(),
                     [target](const RawColumn& c) { return c.target == target; });
}

bool AnyIncrement(const ImportRecipe& recipe, ColumnTarget first, ColumnTarget last) {
  return std::any_of(recipe.columns.begin(), recipe.columns.end(), [&](const RawColumn& c) {
    return c.target >= first && c.target <= last && c.unit.increment;
  });
}

double MedianStep(const std::vector<engine::ImuSample>& samples) {
  std::vector<double> steps;
  steps.reserve(samples.size());
  for (std::size_t k = 1; k < samples.size(); ++k) steps.push_back(samples[k].t_s - samples[k - 1].t_s);
  if (steps.empty()) return 0.0;
  std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
  return steps[steps.size() / 2];
}

// Step 2: the time base, relative to the start of the first sample's interval.
absl::Status SettleTime(const ImportRecipe& recipe, const RecordLocator& where, DecodedRecords& records,
                        engine::BenchRunMetadata& metadata) {
  auto& samples = records.samples;
  if (!HasColumn(recipe, ColumnTarget::kTime)) {
    if (!recipe.interval_s.has_value()) {
      return Refusal({"settings", 0, 0, "columns"}, "no column is t: give the rate (--rate-hz) or interval_s");
    }
    for (std::size_t k = 0; k < samples.size(); ++k) samples[k].t_s = static_cast<double>(k + 1) * *recipe.interval_s;
    if (recipe.start_time_s != 0.0) metadata.extra.emplace_back("time_origin_s", absl::StrFormat("%.17g", recipe.start_time_s));
    return absl::OkStatus();
  }
  for (std::size_t k = 1; k < samples.size(); ++k) {
    if (!(samples[k].t_s > samples[k - 1].t_s)) {
      return Refusal(where.OfSample(k, benchrun::SampleField::kT),
                     absl::StrFormat("%.17g does not follow %.17g: t must increase", samples[k].t_s, samples[k - 1].t_s));
    }
  }
  const double nominal = recipe.interval_s.value_or(MedianStep(samples));
  const double origin = samples.front().t_s - nominal;
  for (auto& s : samples) s.t_s -= origin;
  metadata.extra.emplace_back("time_origin_s", absl::StrFormat("%.17g", origin));
  if (records.first_gps_week.has_value()) {
    metadata.extra.emplace_back("time_origin_gps_week", absl::StrFormat("%.17g", *records.first_gps_week));
  }
  return absl::OkStatus();
}

// Step 3: increments over (t[k−1], t[k]] into mean rates.
void IncrementsToRates(const ImportRecipe& recipe, std::vector<engine::ImuSample>& samples) {
  const bool gyro = AnyIncrement(recipe, ColumnTarget::kGyroX, ColumnTarget::kGyroZ);
  const bool acc = AnyIncrement(recipe, ColumnTarget::kAccX, ColumnTarget::kAccZ);
  if (!gyro && !acc) return;
  // Columns of a triple share increment-ness after the axis turn only if
  // they shared it before; a mixed triple is refused in CheckIncrementTriples.
  // With t implied by a rate, every interval is the nominal one exactly.
  const bool implied = !HasColumn(recipe, ColumnTarget::kTime);
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const double dt = implied ? *recipe.interval_s : k == 0 ? samples[0].t_s : samples[k].t_s - samples[k - 1].t_s;
    if (gyro) samples[k].gyro_rad_s /= dt;
    if (acc) samples[k].acc_mps2 /= dt;
  }
}

absl::Status CheckIncrementTriples(const ImportRecipe& recipe) {
  for (auto [first, last, name] : {std::tuple{ColumnTarget::kGyroX, ColumnTarget::kGyroZ, "gyro"},
                                   std::tuple{ColumnTarget::kAccX, ColumnTarget::kAccZ, "acc"}}) {
    int increments = 0;
    for (const RawColumn& c : recipe.columns) increments += c.target >= first && c.target <= last && c.unit.increment;
    if (increments != 0 && increments != 3) {
      return Refusal({"settings", 0, 0, "units"},
                     absl::StrFormat("the %s columns mix rates and increments: give all three alike", name));
    }
  }
  return absl::OkStatus();
}

// Step 4, levelled: the mean force and rate over the static window.
absl::StatusOr<Eigen::Vector3d> LevelledAttitude(const ImportRecipe& recipe, const std::vector<engine::ImuSample>& samples,
                                                 engine::BenchRunMetadata& metadata) {
  const double window_end_s = recipe.level_window_s.value_or(samples.back().t_s);
  Eigen::Vector3d force = Eigen::Vector3d::Zero(), rate = Eigen::Vector3d::Zero();
  std::size_t n = 0;
  for (const auto& s : samples) {
    if (s.t_s > window_end_s && n > 0) break;
    force += s.acc_mps2;
    rate += s.gyro_rad_s;
    ++n;
  }
  force /= static_cast<double>(n);
  rate /= static_cast<double>(n);
  if (rate.norm() > kStaticMeanRateLimitRadS) {
    return Refusal({"settings", 0, 0, "level_window_s"},
                   absl::StrFormat("the unit turns at a mean %.3g rad/s over 0–%.6g s, so it cannot be levelled there: "
                                   "give a static window (level_window_s) or the attitude",
                                   rate.norm(), window_end_s));
  }
  const Eigen::Vector3d rpy = engine::nav::CoarseAlignment(force, rate, recipe.heading_rad);
  metadata.extra.emplace_back(
      "reference_attitude",
      absl::StrFormat("constant, levelled from the mean specific force over 0-%.6g s%s", window_end_s,
                      recipe.heading_rad.has_value() ? ", heading given" : ", heading gyro-compassed from the mean rate"));
  return rpy;
}

absl::Status SetAttitude(const ImportRecipe& recipe, DecodedRecords& records, engine::BenchRunMetadata& metadata) {
  auto& samples = records.samples;
  if (recipe.attitude == AttitudeSource::kColumns) {
    for (ColumnTarget t : {ColumnTarget::kRefRoll, ColumnTarget::kRefPitch, ColumnTarget::kRefYaw}) {
      if (!HasColumn(recipe, t)) {
        return Refusal({"settings", 0, 0, "attitude"}, "is columns, but ref_roll, ref_pitch and ref_yaw are not all mapped");
      }
    }
    return absl::OkStatus();
  }
  // An attitude given, levelled or turned by a table-yaw column from a given
  // start is as accurate as that start only: not a reading to observe.
  if (!metadata.DeclaredAttitudeReadout().has_value()) metadata.DeclareAttitudeReadout(false);
  Eigen::Vector3d initial = recipe.constant_rpy_rad;
  if (recipe.attitude == AttitudeSource::kLevelled) {
    INSDIAG_ASSIGN_OR_RETURN(auto levelled, LevelledAttitude(recipe, samples, metadata));
    initial = levelled;
  } else {
    metadata.extra.emplace_back("reference_attitude", "constant, given");
  }
  const bool table = !records.table_yaw_rad.empty();
  for (std::size_t k = 0; k < samples.size(); ++k) {
    samples[k].ref_rpy_rad = initial;
    if (table) {
      // Yaw wrapped into (−π, π], as the bench-run writer and reader hold it.
      const double yaw = initial.z() + records.table_yaw_rad[k] - records.table_yaw_rad[0];
      samples[k].ref_rpy_rad.z() = std::remainder(yaw, 2.0 * std::numbers::pi);
    }
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<engine::BenchRun> ImportBenchRun(std::string_view bytes, std::string_view source_name,
                                                const ImportSettings& settings) {
  INSDIAG_ASSIGN_OR_RETURN(auto recipe, RecipeFromSettings(settings));
  if (absl::Status st = CheckIncrementTriples(recipe); !st.ok()) return st;
  INSDIAG_ASSIGN_OR_RETURN(auto records,
                           recipe.format == LogFormat::kText
                               ? internal::ReadTextRecords(bytes, source_name, recipe)
                               : internal::ReadBinaryRecords(bytes, source_name, recipe));
  const RecordLocator where(std::string(source_name), records, recipe.format == LogFormat::kBinary);
  if (records.samples.empty()) return Refusal(where.OfSampleList(), "the log holds no record");

  engine::BenchRun run;
  run.metadata = recipe.metadata;
  run.has_temperature = HasColumn(recipe, ColumnTarget::kTemp);
  if (!recipe.source_description.empty())
    run.metadata.extra.emplace_back("imported_from", recipe.source_description);
  if (absl::Status st = SettleTime(recipe, where, records, run.metadata); !st.ok()) return st;
  IncrementsToRates(recipe, records.samples);
  if (absl::Status st = SetAttitude(recipe, records, run.metadata); !st.ok()) return st;
  run.samples = std::move(records.samples);
  // The bench-run rules (units, ranges, gaps, gravity), naming the log's lines.
  INSDIAG_ASSIGN_OR_RETURN(auto validator, benchrun::BenchRunValidator::Create(
                                               run.metadata, run.has_temperature, where));
  if (absl::Status st = validator.Add(run.samples); !st.ok()) return st;
  if (absl::Status st = validator.Finish(); !st.ok()) return st;
  return run;
}

absl::StatusOr<engine::BenchRun> ImportBenchRunFile(const std::filesystem::path& path, const ImportSettings& settings) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(path.string() + ": cannot be read");
  std::ostringstream bytes;
  bytes << in.rdbuf();
  const std::string log = bytes.str();
  ImportSettings layered;
  if (const Setting* preset = settings.Find("preset")) {
    INSDIAG_ASSIGN_OR_RETURN(auto from_preset, PresetSettings(preset->value, log, path.string()));
    layered.Merge(from_preset);
  }
  layered.Merge(settings);
  return ImportBenchRun(log, path.string(), layered);
}

}  // namespace insdiag::importers
