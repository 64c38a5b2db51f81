// Named presets: the settings of a vendor's log layout, so that such a log
// imports with `--preset NAME` and the facts only the user knows (serial,
// site when the log lacks it, count scales when they depend on the IMU).
//
//   psins-imu         the PSINS toolbox's SIMU text log: `%` comment lines,
//                     three header lines (initial attitude and velocity; site,
//                     t0, interval [ms] and g; gyro scale [arcsec] and
//                     accelerometer scale [µg·s] per count), then one line of
//                     six integer counts per sample, axes X-right, Y-forward,
//                     Z-up. A log without the header is read as the toolbox's
//                     in-memory layout: wx wy wz [rad] vx vy vz [m/s] t [s].
//   novatel-rawimusa  NovAtel's short ASCII RAWIMUSA log (`%RAWIMUSA,…;week,
//                     seconds,status,z acc,−y acc,x acc,z gyro,−y gyro,x gyro
//                     *crc`), increments in counts whose scales depend on the
//                     IMU: give them as units (gyro=SCALE*rad,acc=SCALE*m/s).
//                     The CRC of every record is checked; other logs in the
//                     file are skipped.
//   novatel-rawimusxa the extended RAWIMUSXA log: the same, with the IMU info
//                     and IMU type fields before the week.
#pragma once

#include <absl/status/statusor.h>

#include <string>
#include <string_view>
#include <vector>

#include "insdiag/importers/import_settings.h"

namespace insdiag::importers {

// The names of the presets, for help texts.
std::vector<std::string> PresetNames();

// The preset's settings for this log. Some presets read their settings from
// the log's own header; refusals name the log's line.
absl::StatusOr<ImportSettings> PresetSettings(std::string_view preset, std::string_view log_bytes,
                                              std::string_view source_name);

}  // namespace insdiag::importers
