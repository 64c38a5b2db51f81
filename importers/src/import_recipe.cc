#include "insdiag/importers/import_recipe.h"

#include <absl/strings/str_cat.h>
#include <absl/strings/numbers.h>
#include <absl/strings/str_format.h>
#include <absl/strings/str_split.h>

#include <cmath>
#include <functional>
#include <map>
#include <numbers>

#include "insdiag/benchrun/bench_run_validation.h"
#include "insdiag/benchrun/numbers.h"
#include "insdiag/engine/status_macros.h"
#include "text_fields.h"

namespace insdiag::importers {

using benchrun::FiniteNumber;
using internal::Split;
using internal::Trim;
namespace {

using benchrun::Refusal;

constexpr double kRadPerDeg = std::numbers::pi / 180.0;
constexpr double kRadPerArcsec = kRadPerDeg / 3600.0;
constexpr double kMetresPerFoot = 0.3048;  // international foot
// The standard acceleration of gravity (CGPM 1901), the default g of the
// units g, mg and ug.s; a log that states its own g sets g_mps2.
constexpr double kStandardGravityMps2 = 9.80665;

struct NamedTarget {
  std::string_view name;
  ColumnTarget target;
};
constexpr NamedTarget kTargets[] = {
    {"t", ColumnTarget::kTime},           {"gps_week", ColumnTarget::kGpsWeek},
    {"gyro_x", ColumnTarget::kGyroX},     {"gyro_y", ColumnTarget::kGyroY},
    {"gyro_z", ColumnTarget::kGyroZ},     {"acc_x", ColumnTarget::kAccX},
    {"acc_y", ColumnTarget::kAccY},       {"acc_z", ColumnTarget::kAccZ},
    {"ref_roll", ColumnTarget::kRefRoll}, {"ref_pitch", ColumnTarget::kRefPitch},
    {"ref_yaw", ColumnTarget::kRefYaw},   {"table_yaw", ColumnTarget::kTableYaw},
    {"temp", ColumnTarget::kTemp},
};

std::optional<ColumnTarget> TargetNamed(std::string_view name) {
  if (name == "-" || name == "skip") return ColumnTarget::kSkip;
  for (const NamedTarget& t : kTargets) {
    if (t.name == name) return t.target;
  }
  return std::nullopt;
}

// The unit group a column belongs to, as named in `units:` ("gyro").
std::string_view GroupOf(ColumnTarget target) {
  switch (target) {
    case ColumnTarget::kGyroX:
    case ColumnTarget::kGyroY:
    case ColumnTarget::kGyroZ: return "gyro";
    case ColumnTarget::kAccX:
    case ColumnTarget::kAccY:
    case ColumnTarget::kAccZ: return "acc";
    case ColumnTarget::kRefRoll:
    case ColumnTarget::kRefPitch:
    case ColumnTarget::kRefYaw: return "ref";
    case ColumnTarget::kTableYaw: return "table_yaw";
    case ColumnTarget::kTime: return "t";
    case ColumnTarget::kTemp: return "temp";
    case ColumnTarget::kGpsWeek:
    case ColumnTarget::kSkip: return "";
  }
  return "";
}

std::string_view NameOf(ColumnTarget target) {
  for (const NamedTarget& t : kTargets) {
    if (t.target == target) return t.name;
  }
  return "-";
}

struct UnitEntry {
  std::string_view group;
  std::string_view name;
  double to_si;  // g-based units are scaled by g at parse time
  bool increment;
  bool per_g;
};
constexpr UnitEntry kUnits[] = {
    {"gyro", "rad/s", 1.0, false, false},
    {"gyro", "deg/s", kRadPerDeg, false, false},
    {"gyro", "deg/h", kRadPerDeg / 3600.0, false, false},
    {"gyro", "rad", 1.0, true, false},
    {"gyro", "deg", kRadPerDeg, true, false},
    {"gyro", "arcsec", kRadPerArcsec, true, false},
    {"acc", "m/s2", 1.0, false, false},
    {"acc", "g", 1.0, false, true},
    {"acc", "mg", 1e-3, false, true},
    {"acc", "m/s", 1.0, true, false},
    {"acc", "ft/s", kMetresPerFoot, true, false},
    {"acc", "ug.s", 1e-6, true, true},
    {"t", "s", 1.0, false, false},
    {"t", "ms", 1e-3, false, false},
    {"t", "us", 1e-6, false, false},
    {"t", "ns", 1e-9, false, false},
    {"ref", "rad", 1.0, false, false},
    {"ref", "deg", kRadPerDeg, false, false},
    {"table_yaw", "rad", 1.0, false, false},
    {"table_yaw", "deg", kRadPerDeg, false, false},
    {"temp", "degC", 1.0, false, false},
};

// The bench-run format's own unit of a group: the first listed.
std::string_view SiUnitOf(std::string_view group) {
  for (const UnitEntry& u : kUnits) {
    if (u.group == group) return u.name;
  }
  return "";
}

std::string UnitsOfGroup(std::string_view group) {
  std::string names;
  for (const UnitEntry& u : kUnits) {
    if (u.group == group) names.append(names.empty() ? "" : ", ").append(u.name);
  }
  return names;
}

absl::StatusOr<double> Number(const Setting& s) {
  const std::optional<double> value = FiniteNumber(s.value);
  if (!value.has_value()) return Refusal(s.origin, absl::StrFormat("'%s' is not a finite number", s.value));
  return *value;
}

absl::StatusOr<int> NonNegativeInt(const Setting& s) {
  const std::optional<int> value = internal::WholeNumber<int>(s.value);
  if (!value.has_value() || *value < 0) {
    return Refusal(s.origin, absl::StrFormat("'%s' is not a whole number ≥ 0", s.value));
  }
  return *value;
}

}  // namespace

absl::StatusOr<ColumnUnit> ParseUnit(ColumnTarget target, std::string_view text, double g_mps2) {
  const std::string_view group = GroupOf(target);
  double scale = 1.0;
  std::string_view name = Trim(text);
  if (const std::size_t star = name.find('*'); star != std::string_view::npos) {
    const std::optional<double> count_scale = FiniteNumber(Trim(name.substr(0, star)));
    if (!count_scale.has_value() || *count_scale == 0.0) {
      return absl::InvalidArgumentError(
          absl::StrFormat("'%s': the count scale before '*' is not a finite, non-zero number", text));
    }
    scale = *count_scale;
    name = Trim(name.substr(star + 1));
  }
  for (const UnitEntry& u : kUnits) {
    if (u.group == group && u.name == name) {
      return ColumnUnit{scale * u.to_si * (u.per_g ? g_mps2 : 1.0), u.increment, std::string(text)};
    }
  }
  return absl::InvalidArgumentError(absl::StrFormat("'%s' is not a unit of %s (%s, each optionally SCALE*unit)",
                                                    text, NameOf(target), UnitsOfGroup(group)));
}

namespace {

std::optional<BinaryType> BinaryTypeNamed(std::string_view name) {
  if (name == "f32") return BinaryType::kFloat32;
  if (name == "f64") return BinaryType::kFloat64;
  if (name == "i16") return BinaryType::kInt16;
  if (name == "i32") return BinaryType::kInt32;
  return std::nullopt;
}

// "t,gyro_x:f32,-acc_y,-": targets, signs and binary types.
absl::Status ParseColumns(const Setting& s, std::vector<RawColumn>& columns) {
  columns.clear();
  std::vector<bool> seen(std::size(kTargets) + 2, false);
  for (std::string_view entry : Split(s.value, ',')) {
    RawColumn column;
    column.name = std::string(entry);
    if (const std::size_t colon = entry.find(':'); colon != std::string_view::npos) {
      const std::optional<BinaryType> type = BinaryTypeNamed(entry.substr(colon + 1));
      if (!type.has_value()) {
        return Refusal(s.origin, absl::StrFormat("'%s': the type is one of f32, f64, i16, i32", entry));
      }
      column.binary_type = *type;
      entry = entry.substr(0, colon);
    }
    if (entry.size() > 1 && entry.front() == '-') {
      column.sign = -1.0;
      entry.remove_prefix(1);
    }
    const std::optional<ColumnTarget> target = TargetNamed(entry);
    if (!target.has_value()) {
      return Refusal(s.origin, absl::StrFormat("'%s' is not a column: t, gps_week, gyro_x..z, acc_x..z, "
                                               "ref_roll, ref_pitch, ref_yaw, table_yaw, temp, or - to skip",
                                               column.name));
    }
    column.target = *target;
    const auto index = static_cast<std::size_t>(*target);
    if (*target != ColumnTarget::kSkip && seen[index]) {
      return Refusal(s.origin, absl::StrFormat("'%s' is mapped twice", entry));
    }
    seen[index] = true;
    columns.push_back(std::move(column));
  }
  for (ColumnTarget needed : {ColumnTarget::kGyroX, ColumnTarget::kGyroY, ColumnTarget::kGyroZ,
                              ColumnTarget::kAccX, ColumnTarget::kAccY, ColumnTarget::kAccZ}) {
    if (!seen[static_cast<std::size_t>(needed)]) {
      return Refusal(s.origin, absl::StrFormat("no column is %s", NameOf(needed)));
    }
  }
  return absl::OkStatus();
}

// "x=-y,y=x,z=-z": body axis = ± sensor axis; a proper rotation only.
absl::Status ParseAxes(const Setting& s, ImportRecipe& recipe) {
  std::array<bool, 3> body_given{}, sensor_used{};
  for (std::string_view entry : Split(s.value, ',')) {
    const std::string_view why = "an entry is BODY=[-]SENSOR with axes x, y, z, e.g. x=-y";
    if (entry.size() < 3 || entry[1] != '=') return Refusal(s.origin, absl::StrFormat("'%s': %s", entry, why));
    const int body = entry[0] - 'x';
    std::string_view sensor_text = entry.substr(2);
    double sign = 1.0;
    if (sensor_text.size() == 2 && sensor_text[0] == '-') {
      sign = -1.0;
      sensor_text.remove_prefix(1);
    }
    const int sensor = sensor_text.size() == 1 ? sensor_text[0] - 'x' : -1;
    if (body < 0 || body > 2 || sensor < 0 || sensor > 2) {
      return Refusal(s.origin, absl::StrFormat("'%s': %s", entry, why));
    }
    if (body_given[body] || sensor_used[sensor]) {
      return Refusal(s.origin, absl::StrFormat("'%s': each axis appears once on each side", entry));
    }
    body_given[body] = sensor_used[sensor] = true;
    recipe.axis_source[body] = sensor;
    recipe.axis_sign[body] = sign;
  }
  if (!(body_given[0] && body_given[1] && body_given[2])) {
    return Refusal(s.origin, "give all three body axes, e.g. x=y,y=x,z=-z");
  }
  // The determinant of a signed permutation: its signs times the parity.
  const auto& a = recipe.axis_source;
  const int inversions = (a[0] > a[1]) + (a[0] > a[2]) + (a[1] > a[2]);
  const double det = recipe.axis_sign[0] * recipe.axis_sign[1] * recipe.axis_sign[2] * (inversions % 2 ? -1 : 1);
  if (det < 0) {
    return Refusal(s.origin, "turns a right-handed frame into a left-handed one; the body axes are right-handed "
                             "(flip the sign of one axis more, or one less)");
  }
  return absl::OkStatus();
}

// "gyro=deg/s,acc_z=g,t=ms": by group or by column name.
absl::Status ApplyUnits(const Setting* s, ImportRecipe& recipe) {
  std::map<std::string, std::string, std::less<>> given;
  if (s != nullptr) {
    for (std::string_view entry : Split(s->value, ',', /*skip_empty=*/true)) {
      const std::size_t eq = entry.find('=');
      if (eq == std::string_view::npos) {
        return Refusal(s->origin, absl::StrFormat("'%s' is not NAME=UNIT, e.g. gyro=deg/s", entry));
      }
      given[std::string(Trim(entry.substr(0, eq)))] =
          std::string(Trim(entry.substr(eq + 1)));
    }
  }
  std::map<std::string, bool, std::less<>> used;
  for (RawColumn& column : recipe.columns) {
    if (column.target == ColumnTarget::kSkip || column.target == ColumnTarget::kGpsWeek) continue;
    const std::string name(NameOf(column.target));
    const std::string group(GroupOf(column.target));
    auto it = given.find(name);
    if (it == given.end()) it = given.find(group);
    // Without a unit, a column is in the bench-run format's own SI unit.
    const std::string text = it != given.end() ? it->second : std::string(SiUnitOf(group));
    if (it != given.end()) used[it->first] = true;
    auto unit = ParseUnit(column.target, text, recipe.g_mps2);
    if (!unit.ok()) {
      return Refusal(s != nullptr ? s->origin : benchrun::InputLocation{"settings", 0, 0, "units"},
                     std::string(unit.status().message()));
    }
    column.unit = *std::move(unit);
  }
  for (const auto& [name, unit] : given) {
    if (!used.contains(name)) {
      return Refusal(s->origin, absl::StrFormat("'%s' names no mapped column or group (gyro, acc, t, ref, "
                                                "table_yaw, temp, or a column name)", name));
    }
  }
  return absl::OkStatus();
}

}  // namespace

namespace {

// The bench-run metadata a setting may give (shared/spec/bench-run-format.md).
absl::Status ApplyMetadata(const Setting& s, engine::BenchRunMetadata& m, bool& handled) {
  handled = true;
  const auto number = [&](std::optional<double>& into) -> absl::Status {
    INSDIAG_ASSIGN_OR_RETURN(auto v, Number(s));
    into = v;
    return absl::OkStatus();
  };
  const auto degrees = [&](double& into) -> absl::Status {
    const std::optional<double> radians = benchrun::SiteAngleRadians(s.value);
    if (!radians.has_value()) return Refusal(s.origin, absl::StrFormat("'%s' is not a finite number", s.value));
    into = *radians;
    return absl::OkStatus();
  };
  const std::string_view k = s.key;
  if (k == "unit_serial") m.unit_serial = s.value;
  else if (k == "unit_type") m.unit_type = s.value;
  else if (k == "site_latitude_deg") return degrees(m.site.latitude_rad);
  else if (k == "site_longitude_deg") return degrees(m.site.longitude_rad);
  else if (k == "site_height_m") {
    INSDIAG_ASSIGN_OR_RETURN(auto v, Number(s));
    m.site.height_m = v;
  } else if (k == "gyro_arw") return number(m.datasheet.gyro_arw_rad_rts);
  else if (k == "gyro_bias_sigma") return number(m.datasheet.gyro_bias_sigma_rad_s);
  else if (k == "gyro_bias_tau") return number(m.datasheet.gyro_bias_tau_s);
  else if (k == "acc_vrw") return number(m.datasheet.acc_vrw_mps_rts);
  else if (k == "acc_bias_sigma") return number(m.datasheet.acc_bias_sigma_mps2);
  else if (k == "acc_bias_tau") return number(m.datasheet.acc_bias_tau_s);
  else if (k == "bench" || k == "operator" || k == "started_at" || k == "notes") m.extra.emplace_back(k, s.value);
  else if (k.starts_with("meta.") && k.size() > 5) m.extra.emplace_back(k.substr(5), s.value);
  else handled = false;
  return absl::OkStatus();
}

absl::Status ApplyLayout(const Setting& s, ImportRecipe& r, bool& handled) {
  handled = true;
  const auto integer = [&](int& into) -> absl::Status {
    INSDIAG_ASSIGN_OR_RETURN(auto v, NonNegativeInt(s));
    into = v;
    return absl::OkStatus();
  };
  const std::string_view k = s.key;
  if (k == "log_format") {
    if (s.value == "text") r.format = LogFormat::kText;
    else if (s.value == "binary") r.format = LogFormat::kBinary;
    else return Refusal(s.origin, absl::StrFormat("'%s' is not text or binary", s.value));
  } else if (k == "delimiters") {
    r.text.delimiters = s.value == "whitespace" ? " \t" : s.value == "comma" ? "," : s.value;
  } else if (k == "skip_lines") return integer(r.text.skip_lines);
  else if (k == "comment_prefixes") r.text.comment_prefixes = s.value;
  else if (k == "line_prefix") r.text.line_prefix = s.value;
  else if (k == "checksum") {
    if (s.value == "none") r.text.checksum = Checksum::kNone;
    else if (s.value == "novatel-crc32") r.text.checksum = Checksum::kNovatelCrc32;
    else return Refusal(s.origin, absl::StrFormat("'%s' is not none or novatel-crc32", s.value));
  } else if (k == "header_bytes") return integer(r.binary.header_bytes);
  else if (k == "record_bytes") return integer(r.binary.record_bytes);
  else if (k == "record_lead_bytes") return integer(r.binary.record_lead_bytes);
  else handled = false;
  return absl::OkStatus();
}

absl::Status ApplyTimeAndAttitude(const Setting& s, ImportRecipe& r, bool& handled) {
  handled = true;
  const std::string_view k = s.key;
  auto value = [&]() { return Number(s); };
  if (k == "rate_hz" || k == "interval_s") {
    INSDIAG_ASSIGN_OR_RETURN(auto v, value());
    if (v <= 0) return Refusal(s.origin, "must be positive");
    r.interval_s = k == "rate_hz" ? 1.0 / v : v;
  } else if (k == "start_time_s") {
    INSDIAG_ASSIGN_OR_RETURN(auto v, value());
    r.start_time_s = v;
  } else if (k == "window_s") {
    const std::vector<absl::string_view> ends = absl::StrSplit(s.value, ',');
    double from = 0.0, to = 0.0;
    if (ends.size() != 2 || !absl::SimpleAtod(ends[0], &from) || !absl::SimpleAtod(ends[1], &to) ||
        !std::isfinite(from) || !std::isfinite(to) || from < 0.0 || !(to > from)) {
      return Refusal(s.origin, absl::StrFormat("'%s' is not FROM,TO in seconds since the first record, 0 ≤ FROM < TO",
                                               s.value));
    }
    r.window_s = std::pair{from, to};
  } else if (k == "attitude") {
    if (s.value == "constant") r.attitude = AttitudeSource::kConstant;
    else if (s.value == "level") r.attitude = AttitudeSource::kLevelled;
    else if (s.value == "columns") r.attitude = AttitudeSource::kColumns;
    else return Refusal(s.origin, absl::StrFormat("'%s' is not constant, level or columns", s.value));
  } else if (k == "ref_roll_deg" || k == "ref_pitch_deg" || k == "ref_yaw_deg") {
    INSDIAG_ASSIGN_OR_RETURN(auto v, value());
    r.constant_rpy_rad[k == "ref_roll_deg" ? 0 : k == "ref_pitch_deg" ? 1 : 2] = v * kRadPerDeg;
  } else if (k == "heading_deg") {
    INSDIAG_ASSIGN_OR_RETURN(auto v, value());
    r.heading_rad = v * kRadPerDeg;
  } else if (k == "level_window_s") {
    INSDIAG_ASSIGN_OR_RETURN(auto v, value());
    if (v <= 0) return Refusal(s.origin, "must be positive");
    r.level_window_s = v;
  } else if (k == "g_mps2" || k == "columns" || k == "units" || k == "axes" || k == "binary_type" ||
             k == "source" || k == "preset") {
    // Read in order by RecipeFromSettings: they depend on one another.
  } else {
    handled = false;
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<ImportRecipe> RecipeFromSettings(const ImportSettings& settings) {
  ImportRecipe recipe;
  recipe.metadata.format = std::string(benchrun::kFormatV1);
  recipe.g_mps2 = kStandardGravityMps2;
  if (const Setting* g = settings.Find("g_mps2")) {
    INSDIAG_ASSIGN_OR_RETURN(auto v, Number(*g));
    recipe.g_mps2 = v;
  }
  // Settings of one key may come from several layers: only the winner counts.
  std::map<std::string, bool, std::less<>> applied;
  for (auto it = settings.All().rbegin(); it != settings.All().rend(); ++it) {
    if (applied[it->key]) continue;
    applied[it->key] = true;
    if (!it->required_because.empty()) {
      return Refusal({it->origin.source, 0, 0, it->key}, "is required: " + it->required_because);
    }
    bool handled = false;
    for (auto apply : {+[](const Setting& s, ImportRecipe& r, bool& h) { return ApplyMetadata(s, r.metadata, h); },
                       +[](const Setting& s, ImportRecipe& r, bool& h) { return ApplyLayout(s, r, h); },
                       +[](const Setting& s, ImportRecipe& r, bool& h) { return ApplyTimeAndAttitude(s, r, h); }}) {
      if (absl::Status st = apply(*it, recipe, handled); !st.ok()) return st;
      if (handled) break;
    }
    if (!handled) return Refusal(it->origin, "is not a setting of an import (docs/IMPORT.md)");
  }
  const Setting* columns = settings.Find("columns");
  if (columns == nullptr) return Refusal({"settings", 0, 0, "columns"}, "is missing: say which column holds what");
  if (absl::Status st = ParseColumns(*columns, recipe.columns); !st.ok()) return st;
  if (const Setting* type = settings.Find("binary_type")) {
    const std::optional<BinaryType> all = BinaryTypeNamed(type->value);
    if (!all.has_value()) return Refusal(type->origin, absl::StrFormat("'%s' is not f32, f64, i16 or i32", type->value));
    for (RawColumn& column : recipe.columns) {
      if (column.name.find(':') == std::string::npos) column.binary_type = *all;  // a column's own type wins
    }
  }
  if (absl::Status st = ApplyUnits(settings.Find("units"), recipe); !st.ok()) return st;
  if (const Setting* axes = settings.Find("axes")) {
    if (absl::Status st = ParseAxes(*axes, recipe); !st.ok()) return st;
  }
  if (const Setting* source = settings.Find("source")) recipe.source_description = source->value;
  // The bench-run format requires these; a log seldom holds them.
  for (std::string_view key : {"unit_serial", "site_latitude_deg", "site_longitude_deg", "site_height_m"}) {
    if (settings.Find(key) == nullptr) {
      return Refusal({"settings", 0, 0, std::string(key)},
                     "is missing: give it as an option (--serial, --site LAT,LON,HEIGHT) or in the side file");
    }
  }
  return recipe;
}

}  // namespace insdiag::importers
