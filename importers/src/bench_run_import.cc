#include "insdiag/importers/bench_run_import.h"

#include <absl/strings/str_format.h>

#include <Eigen/Geometry>

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

// Over a window where the mean body rate exceeds this (0.57°/s: above the
// bias of any navigation or tactical gyro and Earth's rate by two orders),
// the unit was turning or its gyros are consumer-grade: no heading can be
// gyro-compassed there.
constexpr double kStaticMeanRateLimitRadS = 0.01;
// A unit at rest keeps its specific force's direction: a batch mean of it
// turned by more than a degree from the window's mean is a tilt, far beyond
// what vibration moves a mean of a twentieth of the window.
constexpr double kStaticTiltChangeLimitRad = 1.0 * std::numbers::pi / 180.0;
constexpr std::size_t kLevelBatches = 20;
// A window too short to batch gives no level accuracy of its own: that of a
// precision table's levelling, about an arc-second, is not claimed; a
// milliradian, a bubble level's, is.
constexpr double kUnresolvedLevelSigmaRad = 1e-3;

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
  InputLocation OfMetadata(benchrun::MetadataField field, std::size_t extra_index) const override {
    if (field == benchrun::MetadataField::kExtra && metadata_ != nullptr && extra_index < metadata_->extra.size()) {
      return {"settings", 0, 0, metadata_->extra[extra_index].first};
    }
    return {"settings", 0, 0, std::string(benchrun::MetadataKey(field))};
  }
  // Free metadata is named by its key once the run's metadata is known.
  void SetMetadata(const engine::BenchRunMetadata* metadata) { metadata_ = metadata; }
  InputLocation OfSampleList() const override { return {source_, 0, 0, "records"}; }

 private:
  std::string source_;
  const engine::BenchRunMetadata* metadata_ = nullptr;
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

// Step 1b: the records of the window, in time since the first record (the
// log's own t, or the nominal interval's count when t is implied).
absl::Status KeepWindow(const ImportRecipe& recipe, DecodedRecords& records) {
  if (!recipe.window_s.has_value()) return absl::OkStatus();
  const auto [from_s, to_s] = *recipe.window_s;
  const bool implied = !HasColumn(recipe, ColumnTarget::kTime);
  const double first_t = records.samples.front().t_s;
  std::size_t kept = 0;
  for (std::size_t k = 0; k < records.samples.size(); ++k) {
    const double since_first_s = implied ? static_cast<double>(k) * *recipe.interval_s : records.samples[k].t_s - first_t;
    if (since_first_s < from_s || since_first_s > to_s) continue;
    records.samples[kept] = records.samples[k];
    records.origin[kept] = records.origin[k];
    if (!records.table_yaw_rad.empty()) records.table_yaw_rad[kept] = records.table_yaw_rad[k];
    ++kept;
  }
  if (kept < 2) {
    return Refusal({"settings", 0, 0, "window_s"},
                   absl::StrFormat("keeps %d record(s) of %d: the window %.6g–%.6g s lies outside the log", kept,
                                   records.samples.size(), from_s, to_s));
  }
  records.samples.resize(kept);
  records.origin.resize(kept);
  if (!records.table_yaw_rad.empty()) records.table_yaw_rad.resize(kept);
  return absl::OkStatus();
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

// The steady rate over the first n samples: the least-squares slope of the
// integrated angle. The mean rate is the angle's change between the window's
// ends, so a stand that settles from a swing at the start (a ring-down of a
// few milliradians), or is knocked near the end, moves it by the whole swing
// over the window — 0.8° of a gyro-compassed heading on a rocking stand; the
// fitted slope weighs the ends least (a transient of length τ at one end
// moves it by about 6τ/T of its swing over T). nullopt for fewer than three
// samples.
std::optional<Eigen::Vector3d> SteadyRate(const std::vector<engine::ImuSample>& samples, std::size_t n) {
  if (n < 3) return std::nullopt;
  // Sums about the window's first time, so that long logs keep precision.
  const double t0 = samples[0].t_s;
  double s_t = 0.0, s_tt = 0.0;
  Eigen::Vector3d angle = Eigen::Vector3d::Zero(), s_a = Eigen::Vector3d::Zero(), s_ta = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < n; ++k) {
    const double t = samples[k].t_s - t0;
    if (k > 0) angle += samples[k].gyro_rad_s * (samples[k].t_s - samples[k - 1].t_s);
    s_t += t;
    s_tt += t * t;
    s_a += angle;
    s_ta += t * angle;
  }
  const double count = static_cast<double>(n);
  const double spread = count * s_tt - s_t * s_t;
  if (!(spread > 0.0)) return std::nullopt;
  return (count * s_ta - s_t * s_a) / spread;
}

// Step 4, levelled: the attitude at the run's start from the mean specific
// force and rate over the static window, and how well they give it (the
// bench-run format's reference_*_sigma_rad).
//
// A unit at rest on a bench that settles, or on a vehicle, rocks by
// milliradians while the window runs, and the gyros measure it: a body that
// turned by θ since the start reads a fixed vector f as (I − [θ×]) f₀
// (small angles; Titterton & Weston, §3.6), so f₀ = f + θ × f takes each
// sample's force back to the start's axes, with θ the rate less its window
// mean (Earth's and the biases) integrated from the start. The mean of f₀
// levels the start. How far the batch means of f₀ stray from it — the
// accelerometers' wander and the gyros' drift over the window — is the
// level's accuracy at the start.
absl::StatusOr<Eigen::Vector3d> LevelledAttitude(const ImportRecipe& recipe, const std::vector<engine::ImuSample>& samples,
                                                 engine::BenchRunMetadata& metadata) {
  const double window_end_s = recipe.level_window_s.value_or(samples.back().t_s);
  std::size_t n = 0;
  while (n < samples.size() && (samples[n].t_s <= window_end_s || n == 0)) ++n;
  Eigen::Vector3d rate = Eigen::Vector3d::Zero(), force = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < n; ++k) {
    rate += samples[k].gyro_rad_s;
    force += samples[k].acc_mps2;
  }
  rate /= static_cast<double>(n);
  force /= static_cast<double>(n);

  const std::size_t batch = std::max<std::size_t>(1, n / kLevelBatches);
  const std::size_t batches = n / batch;
  std::vector<Eigen::Vector3d> batch_force(batches, Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector3d> batch_force_at_start(batches, Eigen::Vector3d::Zero());
  Eigen::Vector3d turned_rad = Eigen::Vector3d::Zero(), force_at_start = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < n; ++k) {
    const double dt_s = k == 0 ? 0.0 : samples[k].t_s - samples[k - 1].t_s;
    turned_rad += (samples[k].gyro_rad_s - rate) * dt_s;
    const Eigen::Vector3d f0 = samples[k].acc_mps2 + turned_rad.cross(samples[k].acc_mps2);
    force_at_start += f0;
    if (k / batch < batches) {
      batch_force[k / batch] += samples[k].acc_mps2 / static_cast<double>(batch);
      batch_force_at_start[k / batch] += f0 / static_cast<double>(batch);
    }
  }
  force_at_start /= static_cast<double>(n);

  // A batch whose force turned by more than a degree: the unit was moved.
  double tilt_change_rad = 0.0;
  for (const Eigen::Vector3d& m : batch_force) {
    tilt_change_rad = std::max(tilt_change_rad, std::acos(std::clamp(m.normalized().dot(force.normalized()), -1.0, 1.0)));
  }
  if (tilt_change_rad > kStaticTiltChangeLimitRad) {
    return Refusal({"settings", 0, 0, "level_window_s"},
                   absl::StrFormat("the specific force turns by %.3g° over 0–%.6g s, so the unit is not at rest there: "
                                   "give a static window (level_window_s) or the attitude",
                                   tilt_change_rad * 180.0 / std::numbers::pi, window_end_s));
  }
  const Eigen::Vector3d up = force_at_start.normalized();
  double tilt_square_sum_rad2 = 0.0;
  for (const Eigen::Vector3d& m : batch_force_at_start) {
    const Eigen::Vector3d across = (m - force_at_start) - (m - force_at_start).dot(up) * up;
    tilt_square_sum_rad2 += across.squaredNorm() / force_at_start.squaredNorm();
  }
  // Two level axes share the squared deviation across the force.
  const double level_sigma_rad = batches > 1 ? std::sqrt(tilt_square_sum_rad2 / (2.0 * static_cast<double>(batches - 1)))
                                             : kUnresolvedLevelSigmaRad;

  // Gyro-compassing needs the mean rate to be Earth's: a rate far above it
  // is a turn or a consumer gyro's bias, and gives no heading.
  const bool compass = !recipe.heading_rad.has_value() && rate.norm() <= kStaticMeanRateLimitRadS;
  const std::optional<double> heading = recipe.heading_rad.has_value() ? recipe.heading_rad
                                        : compass                       ? std::nullopt
                                                                        : std::optional<double>(0.0);
  const Eigen::Vector3d rpy =
      engine::nav::CoarseAlignment(force_at_start, SteadyRate(samples, n).value_or(rate), heading);
  metadata.extra.emplace_back(
      "reference_attitude",
      absl::StrFormat("constant, levelled at the start from the mean specific force over 0-%.6g s taken back to the start by the gyros%s", window_end_s,
                      recipe.heading_rad.has_value() ? ", heading given"
                      : compass ? ", heading gyro-compassed from the steady rate (the integrated angle's fitted slope)"
                                : ", heading 0: the mean rate is far above Earth's, so it gives none"));
  // A log that reads exactly the same at every sample resolves no level
  // scatter: it states none, and the encoders' accuracy applies.
  if (level_sigma_rad > 0.0) {
    metadata.extra.emplace_back(std::string(engine::kReferenceLevelSigmaKey), absl::StrFormat("%.3g", level_sigma_rad));
  }
  if (!recipe.heading_rad.has_value()) {
    metadata.extra.emplace_back(std::string(engine::kReferenceHeadingSigmaKey), std::string(engine::kHeadingNotSurveyed));
  }
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
  RecordLocator where(std::string(source_name), records, recipe.format == LogFormat::kBinary);
  if (records.samples.empty()) return Refusal(where.OfSampleList(), "the log holds no record");

  engine::BenchRun run;
  run.metadata = recipe.metadata;
  run.has_temperature = HasColumn(recipe, ColumnTarget::kTemp);
  if (!recipe.source_description.empty())
    run.metadata.extra.emplace_back("imported_from", recipe.source_description);
  if (HasColumn(recipe, ColumnTarget::kTime) || recipe.interval_s.has_value()) {
    if (absl::Status st = KeepWindow(recipe, records); !st.ok()) return st;
  }
  if (absl::Status st = SettleTime(recipe, where, records, run.metadata); !st.ok()) return st;
  IncrementsToRates(recipe, records.samples);
  if (absl::Status st = SetAttitude(recipe, records, run.metadata); !st.ok()) return st;
  run.samples = std::move(records.samples);
  // The bench-run rules (units, ranges, gaps, gravity), naming the log's lines.
  where.SetMetadata(&run.metadata);
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
