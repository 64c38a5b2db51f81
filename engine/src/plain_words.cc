#include "insdiag/engine/plain_words.h"

#include <absl/strings/str_format.h>
#include <absl/strings/str_join.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <set>

#include "insdiag/engine/monitor/monitoring.h"

namespace insdiag::engine {
namespace {

// A quality engineer reads gyro biases in °/h and accelerometer biases in mg.
constexpr double kDegPerHourPerRadPerS = 180.0 / std::numbers::pi * 3600.0;
constexpr double kStandardGravityMps2 = 9.80665;  // the mg's g (CGPM 1901)
constexpr double kRawWindowS = 60.0;              // "the minute means either side"
constexpr int kMaxFindings = 3;

struct SensorChannel {
  bool gyro = true;
  int axis = 0;
};

// "gyro_bias_step.x" → gyro x; false for a name on no sensor axis.
bool ChannelOf(const std::string& name, SensorChannel& channel) {
  const bool gyro = name.starts_with("gyro");
  if (!gyro && !name.starts_with("acc")) return false;
  const char axis = name.empty() ? ' ' : name.back();
  if (axis < 'x' || axis > 'z' || name.size() < 2 || name[name.size() - 2] != '.') return false;
  channel = {gyro, axis - 'x'};
  return true;
}

std::string Reading(const SensorChannel& c, double si) {
  return c.gyro ? absl::StrFormat("%.3g °/h", si * kDegPerHourPerRadPerS)
                : absl::StrFormat("%.3g mg", si / kStandardGravityMps2 * 1e3);
}

// The raw mean of a channel over [from, to) s, NaN where no sample lies.
double RawMean(const BenchRun& run, const SensorChannel& c, double from_s, double to_s) {
  double sum = 0.0;
  int n = 0;
  for (const ImuSample& s : run.samples) {
    if (s.t_s < from_s || s.t_s >= to_s) continue;
    sum += (c.gyro ? s.gyro_rad_s : s.acc_mps2)[c.axis];
    ++n;
  }
  return n > 0 ? sum / n : std::nan("");
}

std::string SensorName(const SensorChannel& c) {
  return absl::StrFormat("%s %c", c.gyro ? "gyro" : "accelerometer", static_cast<char>('x' + c.axis));
}

// Two raw means and their change, with the decimals that show the change:
// a 0.6 mg step on a 964 mg reading needs two.
std::string RawChange(const SensorChannel& c, double before_si, double after_si, const char* before_label,
                      const char* after_label) {
  const double scale = c.gyro ? kDegPerHourPerRadPerS : 1e3 / kStandardGravityMps2;
  const char* unit = c.gyro ? "°/h" : "mg";
  const double before = before_si * scale, after = after_si * scale, change = after - before;
  const int decimals =
      change != 0.0 ? std::clamp(1 - static_cast<int>(std::floor(std::log10(std::abs(change)))), 0, 6) : 1;
  return absl::StrFormat("its raw samples read %.*f %s %s and %.*f %s %s, a change of %.2g %s", decimals, before, unit,
                         before_label, decimals, after, unit, after_label, change, unit);
}

// One finding: what changed, when, how sure, and what the raw samples read.
std::string FindingLine(const EffectCandidate& c, const SensorChannel& channel, const BenchRun& run) {
  const bool ramp = c.name.find("_ramp.") != std::string::npos;
  if (!c.onset_s.has_value()) {
    return absl::StrFormat("%s: %s %.3g ± %.2g %s, missing from the model (p %.1g)", SensorName(channel), c.name,
                           c.estimate, c.std_error, c.unit, c.p_value_holm);
  }
  const double onset_s = *c.onset_s;
  std::string line = ramp ? absl::StrFormat("%s drifts by %s a minute from %.0f s (p %.1g)", SensorName(channel),
                                            Reading(channel, c.estimate * kRawWindowS), onset_s, c.p_value_holm)
                          : absl::StrFormat("%s bias stepped by %s at %.0f s (p %.1g)", SensorName(channel),
                                            Reading(channel, c.estimate), onset_s, c.p_value_holm);
  // A step: the minutes either side of its onset; a ramp: the minute before
  // it and the run's last minute, where it has gone furthest.
  const double end_s = run.samples.empty() ? onset_s : run.samples.back().t_s;
  const double before = RawMean(run, channel, onset_s - kRawWindowS, onset_s);
  const double after = ramp ? RawMean(run, channel, end_s - kRawWindowS, end_s + 1.0)
                            : RawMean(run, channel, onset_s, onset_s + kRawWindowS);
  if (std::isfinite(before) && std::isfinite(after)) {
    line += "; " + RawChange(channel, before, after, "in the minute before",
                             ramp ? "in the run's last minute" : "in the minute after");
  }
  return line;
}

std::string VerdictLine(const AnalysisReport& r, int findings) {
  const std::string fit = absl::StrFormat("NIS %.3f, band %.3f–%.3f", r.nis_mean, r.nis_band_low, r.nis_band_high);
  switch (r.verdict) {
    case Verdict::kGood:
      return absl::StrFormat("GOOD: the unit behaves as its error model says over the whole run (%s); no fault found.",
                             fit);
    case Verdict::kOperable: {
      std::set<std::string> channels;
      double first_s = std::numeric_limits<double>::infinity();
      for (const FaultInterval& f : r.faults) {
        channels.insert(f.channel);
        first_s = std::min(first_s, f.start_s);
      }
      if (r.faults.empty()) {
        return absl::StrFormat("OPERABLE: no sensor fault stands, but the model's fit is outside its band (%s).", fit);
      }
      return absl::StrFormat(
          "OPERABLE: no sensor fault stands, but the model misfits in %d interval(s) on %s, the first at %.0f s (%s).",
          static_cast<int>(r.faults.size()), absl::StrJoin(channels, ", "), first_s, fit);
    }
    case Verdict::kFaulty:
      return findings > 0
                 ? absl::StrFormat("FAULTY: %d finding(s) the model without them cannot explain (%s):", findings, fit)
                 : absl::StrFormat("FAULTY: the model fails gradually on the observations (%s); see where below.", fit);
  }
  return "";
}

}  // namespace

std::vector<std::string> PlainWordsVerdict(const AnalysisReport& report, const BenchRun& run,
                                           double family_wise_alpha) {
  std::vector<std::string> findings;
  std::set<std::string> modules;
  for (const EffectCandidate& c : report.effect_candidates) {
    SensorChannel channel;
    if (!c.SignificantAt(family_wise_alpha) || !ChannelOf(c.name, channel)) continue;
    // One finding a sensor axis, its most significant: a step and a ramp on
    // one axis are two readings of one change.
    if (modules.count(SensorName(channel)) > 0) continue;
    if (static_cast<int>(findings.size()) == kMaxFindings) break;
    findings.push_back("  " + FindingLine(c, channel, run));
    modules.insert(SensorName(channel));
  }
  std::vector<std::string> lines = {VerdictLine(report, static_cast<int>(findings.size()))};
  lines.insert(lines.end(), findings.begin(), findings.end());
  switch (report.verdict) {
    case Verdict::kGood:
      lines.push_back("To do: nothing; the unit passes.");
      break;
    case Verdict::kOperable:
      lines.push_back("To do: check the bench at those times (a knock, motion, power), and test again if they recur.");
      break;
    case Verdict::kFaulty:
      lines.push_back(modules.empty()
                          ? "To do: read the failure intervals and the localised sensors below, and test again."
                          : absl::StrFormat("To do: check the %s module%s (the change is in %s raw samples), then "
                                            "test again to confirm.",
                                            absl::StrJoin(modules, " and "), modules.size() > 1 ? "s" : "",
                                            modules.size() > 1 ? "their" : "its"));
      break;
  }
  lines.resize(std::min<std::size_t>(lines.size(), kPlainWordsMaxLines));
  return lines;
}

}  // namespace insdiag::engine
