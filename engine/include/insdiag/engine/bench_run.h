// A bench run: what one INS unit produced during one test on a rotary table.
//
// Raw inertial samples plus the table's reference attitude at a fixed,
// surveyed site (spec: shared/spec/bench-run-format.md, version 1). All
// quantities are SI: s, rad/s, m/s², rad, °C.
//
//   gyro_rad_s : body angular rate w.r.t. inertial space, mean over (t[k-1], t[k]]
//   acc_mps2   : specific force in body axes, mean over (t[k-1], t[k]]
//   ref_rpy_rad: attitude of the body w.r.t. local North-East-Down at t[k],
//                C_b^n = Rz(yaw)·Ry(pitch)·Rx(roll)
#pragma once

#include <Eigen/Core>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace insdiag::engine {

// Geodetic WGS-84 position of the table centre.
struct Site {
  double latitude_rad = 0.0;
  double longitude_rad = 0.0;
  double height_m = 0.0;  // ellipsoidal
};

// Datasheet values of the unit, where the run carries them. They form the
// a-priori error model; absent values fall back to the knowledge base or to
// identification from the data.
struct Datasheet {
  std::optional<double> gyro_arw_rad_rts;       // angle random walk [rad/√s]
  std::optional<double> gyro_bias_sigma_rad_s;  // Gauss–Markov drift σ [rad/s]
  std::optional<double> gyro_bias_tau_s;        // Gauss–Markov correlation time [s]
  std::optional<double> acc_vrw_mps_rts;        // velocity random walk [m/s/√s]
  std::optional<double> acc_bias_sigma_mps2;    // Gauss–Markov bias σ [m/s²]
  std::optional<double> acc_bias_tau_s;         // Gauss–Markov correlation time [s]

  bool operator==(const Datasheet&) const = default;
};

// Whether the bench reads the unit's attitude: `# reference_attitude_readout:`
// `encoders` (a rotary table whose encoders are logged with the samples) or
// `none` (a vehicle at rest, an attitude given, levelled or gyro-compassed by
// an importer). Without the key the reference attitude is read from the first
// sample at which it moves within its segment on, for only a table's encoders
// give an attitude that moves with the unit (bench-run-format.md: "from the
// table encoders at t[k]"); while it stays constant it is not, for it may be
// an alignment's estimate or a position given by hand. The rule looks only
// back in time, so that a live test and the stored run agree. Where it is
// read, the filter observes it while the table stands still
// (filter/observation.h); where it is not, the reference attitude is the
// start of the mechanisation only.
inline constexpr std::string_view kReferenceAttitudeReadoutKey = "reference_attitude_readout";
inline constexpr std::string_view kAttitudeReadByEncoders = "encoders";
inline constexpr std::string_view kAttitudeNotRead = "none";

// How accurately the first sample's reference attitude is known (bench-run
// format): `# reference_level_sigma_rad:` the 1σ of roll and pitch (the
// encoders', or a levelling's from the static specific force) and
// `# reference_heading_sigma_rad:` that of the heading, or `unknown` where
// the bench does not survey it. Absent, the encoders' accuracy applies.
inline constexpr std::string_view kReferenceLevelSigmaKey = "reference_level_sigma_rad";
inline constexpr std::string_view kReferenceHeadingSigmaKey = "reference_heading_sigma_rad";
inline constexpr std::string_view kHeadingNotSurveyed = "unknown";

// What a run states of its initial attitude's accuracy.
struct StatedAttitudeAccuracy {
  std::optional<double> level_sigma_rad;    // nullopt: not stated
  std::optional<double> heading_sigma_rad;  // nullopt: not stated, or not surveyed
  bool heading_surveyed = true;             // false: `unknown`
};

struct BenchRunMetadata {
  std::string format;       // "insdiag-bench-run/1"
  std::string unit_serial;  // required
  std::string unit_type;    // optional, e.g. "INS-2000"
  Site site;
  Datasheet datasheet;
  // A multi-position test (BenchRun): the first sample of each segment after
  // the first, increasing; empty for a run of one segment.
  std::vector<size_t> segment_starts;
  // Every other `# key: value` line in file order (bench, operator,
  // started_at, notes and unknown keys), kept as free metadata.
  std::vector<std::pair<std::string, std::string>> extra;

  // Value of a free metadata key, or nullopt.
  std::optional<std::string> Extra(const std::string& key) const;
  // Whether the file says its attitude is read (kReferenceAttitudeReadoutKey), or nullopt.
  std::optional<bool> DeclaredAttitudeReadout() const;
  // Says whether the attitude is read: `encoders` or `none`, replacing what was said.
  void DeclareAttitudeReadout(bool encoders_read);
  // The reference_*_sigma_rad keys, read; values the reader refuses
  // (bench-run CSV) count as not stated.
  StatedAttitudeAccuracy AttitudeAccuracy() const;
};

struct ImuSample {
  double t_s = 0.0;
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d acc_mps2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d ref_rpy_rad = Eigen::Vector3d::Zero();  // roll, pitch, yaw
  double temp_degc = 0.0;  // meaningful only when the run has temperature
};

// Sample `s`'s value on sensor channel `c`: gyro x, y, z, then accelerometer
// x, y, z.
inline double& SensorChannelValue(ImuSample& s, int c) {
  return c < 3 ? s.gyro_rad_s[c] : s.acc_mps2[c - 3];
}
inline double SensorChannelValue(const ImuSample& s, int c) {
  return c < 3 ? s.gyro_rad_s[c] : s.acc_mps2[c - 3];
}

// A test of several segments (docs/MULTI_POSITION.md): files recorded one
// after another with unrecorded moves between them, for example six static
// positions and three turns. Each segment starts from its own reference
// attitude at the site, at rest: the analysis aligns every segment anew and
// shares the sensor errors across them. The samples stay in time order and
// the segments follow one another without a gap, as the joined run holds
// them; the unrecorded move between two segments takes no time in the model.
struct BenchRun {
  BenchRunMetadata metadata;
  bool has_temperature = false;
  std::vector<ImuSample> samples;
  // Whether sample k is the first of a segment after the first.
  bool StartsSegment(size_t k) const;
  // The bench reads the unit's attitude somewhere in the run (kReferenceAttitudeReadoutKey).
  bool ReferenceAttitudeIsRead() const;

  // Nominal sample interval: the median of t[k] − t[k−1]; 0 for < 2 samples.
  double NominalIntervalS() const;
  double DurationS() const;
};

// The median of t[k] − t[k−1] over `samples`; 0 for fewer than two.
double MedianSampleIntervalS(std::span<const ImuSample> samples);

}  // namespace insdiag::engine
