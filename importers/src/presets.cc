#include "insdiag/importers/presets.h"

#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>

#include <array>
#include <cmath>

#include "insdiag/benchrun/bench_run_validation.h"
#include "insdiag/benchrun/numbers.h"
#include "insdiag/engine/status_macros.h"
#include "text_fields.h"

namespace insdiag::importers {

using benchrun::FiniteNumber;
using internal::Split;
using internal::Trim;
namespace {

using benchrun::InputLocation;
using benchrun::Refusal;

// Both vendors' sensor frames are X-right, Y-forward, Z-up; the bench run's
// body axes are x-forward, y-right, z-down.
constexpr std::string_view kRightForwardUpToBody = "x=y,y=x,z=-z";

struct NumberLine {
  std::vector<double> values;
  std::vector<std::string> texts;  // as written, for settings taken verbatim
  int line = 0;
};

// The non-comment lines of a PSINS log's head, as numbers, up to `count`.
absl::StatusOr<std::vector<NumberLine>> LeadingNumberLines(std::string_view log, std::string_view source, int count) {
  std::vector<NumberLine> lines;
  int line_number = 0;
  for (std::string_view line : Split(log, '\n')) {
    ++line_number;
    line = Trim(line);
    if (line.empty() || line.front() == '%') continue;
    NumberLine numbers{{}, {}, line_number};
    for (std::string_view field : Split(line, ' ', /*skip_empty=*/true)) {
      const std::optional<double> v = FiniteNumber(field);
      if (!v.has_value()) {
        return Refusal({std::string(source), line_number, 1, "header"},
                       absl::StrFormat("'%s' is not a number", field));
      }
      numbers.values.push_back(*v);
      numbers.texts.emplace_back(field);
    }
    lines.push_back(std::move(numbers));
    if (static_cast<int>(lines.size()) == count) break;
  }
  return lines;
}

absl::StatusOr<ImportSettings> PsinsImu(std::string_view log, std::string_view source) {
  ImportSettings s;
  const InputLocation preset{"preset psins-imu", 0, 0, ""};
  const auto at = [&](int line, std::string_view key) { return InputLocation{std::string(source), line, 1, std::string(key)}; };
  s.Set("source", "a PSINS toolbox SIMU log (psins-imu preset)", preset);
  s.Set("delimiters", "whitespace", preset);
  s.Set("comment_prefixes", "%", preset);
  s.Set("axes", std::string(kRightForwardUpToBody), preset);
  s.Set("attitude", "level", preset);
  INSDIAG_ASSIGN_OR_RETURN(auto head, LeadingNumberLines(log, source, 3));
  if (!head.empty() && head.front().values.size() == 7) {
    // The toolbox's in-memory layout, saved as text: increments and time.
    s.Set("columns", "gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,t", preset);
    s.Set("units", "gyro=rad,acc=m/s,t=s", preset);
    return s;
  }
  if (head.size() < 3 || (head)[0].values.size() != 6 || (head)[1].values.size() != 6 ||
      (head)[2].values.size() != 6) {
    const int line = head.empty() ? 1 : head.back().line;
    return Refusal(at(line, "header"), "a PSINS SIMU log starts with three lines of six numbers (attitude and "
                                       "velocity; latitude, longitude, height, t0, interval [ms], g; scales), "
                                       "or holds rows of seven (wx wy wz vx vy vz t)");
  }
  const NumberLine& attitude = (head)[0];
  const NumberLine& site = (head)[1];
  const NumberLine& scales = (head)[2];
  s.Set("skip_lines", absl::StrCat(scales.line), preset);
  s.Set("site_latitude_deg", site.texts[0], at(site.line, "site_latitude_deg"));
  s.Set("site_longitude_deg", site.texts[1], at(site.line, "site_longitude_deg"));
  s.Set("site_height_m", site.texts[2], at(site.line, "site_height_m"));
  s.Set("start_time_s", site.texts[3], at(site.line, "start_time_s"));
  s.Set("interval_s", absl::StrFormat("%.17g", site.values[4] * 1e-3), at(site.line, "interval_s"));
  s.Set("g_mps2", site.texts[5], at(site.line, "g_mps2"));
  const std::vector<std::string>& f = scales.texts;
  s.Set("units",
        absl::StrCat("gyro_x=", f[0], "*arcsec,gyro_y=", f[1], "*arcsec,gyro_z=", f[2], "*arcsec,acc_x=", f[3],
                     "*ug.s,acc_y=", f[4], "*ug.s,acc_z=", f[5], "*ug.s"),
        at(scales.line, "units"));
  // The header's own attitude (pitch, roll, yaw in degrees, ENU, "maybe
  // inaccurate") is kept as a note; the reference attitude is levelled.
  s.Set("meta.psins_header_attitude_deg",
        absl::StrCat("pitch ", attitude.texts[0], ", roll ", attitude.texts[1], ", yaw ", attitude.texts[2]),
        at(attitude.line, "attitude"));
  s.Set("columns", "gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z", preset);
  return s;
}

// NovAtel's short-header raw IMU logs: `%RAWIMUSA,week,seconds;` then the
// body; the extended RAWIMUSXA body starts with two more fields (IMU info,
// IMU type).
ImportSettings NovatelRawImu(std::string_view preset_name, std::string_view log_name, bool extended) {
  ImportSettings s;
  const InputLocation preset{absl::StrFormat("preset %s", preset_name), 0, 0, ""};
  s.Set("source", absl::StrFormat("a NovAtel %s log (%s preset)", log_name, preset_name), preset);
  s.Set("line_prefix", absl::StrFormat("%%%s,", log_name), preset);
  s.Set("checksum", "novatel-crc32", preset);
  s.Set("delimiters", ",;", preset);
  // %LOG, log week, log seconds; [IMU info, IMU type;] week, seconds, status,
  // then the increments in the order and signs NovAtel writes them.
  s.Set("columns",
        absl::StrCat("-,-,-,", extended ? "-,-," : "", "gps_week,t,-,acc_z,-acc_y,acc_x,gyro_z,-gyro_y,gyro_x"),
        preset);
  s.Set("axes", std::string(kRightForwardUpToBody), preset);
  s.Set("attitude", "level", preset);
  s.Require("units",
            "the counts' scales depend on the IMU: give them, e.g. --units gyro=RAD_PER_COUNT*rad,acc=MPS_PER_COUNT*m/s",
            preset);
  return s;
}

}  // namespace

std::vector<std::string> PresetNames() { return {"psins-imu", "novatel-rawimusa", "novatel-rawimusxa"}; }

absl::StatusOr<ImportSettings> PresetSettings(std::string_view preset, std::string_view log_bytes,
                                              std::string_view source_name) {
  if (preset == "psins-imu") return PsinsImu(log_bytes, source_name);
  if (preset == "novatel-rawimusa") return NovatelRawImu(preset, "RAWIMUSA", /*extended=*/false);
  if (preset == "novatel-rawimusxa") return NovatelRawImu(preset, "RAWIMUSXA", /*extended=*/true);
  return absl::InvalidArgumentError(
      absl::StrFormat("preset: '%s' is not a preset (psins-imu, novatel-rawimusa, novatel-rawimusxa)", preset));
}

}  // namespace insdiag::importers
