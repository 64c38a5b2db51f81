#include "insdiag/engine/plain_words.h"

#include <absl/strings/str_format.h>
#include <absl/strings/str_join.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <set>

#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/model/parameter_key.h"
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

// "gyro_bias_step.x" → gyro x; false for a name on no single sensor axis.
bool ChannelOf(const std::string& name, SensorChannel& channel) {
  const std::optional<ParameterKey> key = ParseParameterKey(name);
  if (!key.has_value() || !key->sensor.has_value() || key->axes.size() != 1 || key->axis < 0) return false;
  channel = {*key->sensor == Sensor::kGyro, key->axis};
  return true;
}

// A quality engineer's units: °/h for a gyro, mg for an accelerometer.
struct ReadingUnit {
  double per_si;
  const char* name;
};
ReadingUnit UnitOf(const SensorChannel& c) {
  return c.gyro ? ReadingUnit{kDegPerHourPerRadPerS, "°/h"} : ReadingUnit{1e3 / kStandardGravityMps2, "mg"};
}

std::string Reading(const SensorChannel& c, double si) {
  const ReadingUnit unit = UnitOf(c);
  return absl::StrFormat("%.3g %s", si * unit.per_si, unit.name);
}

// The recorded mean of a channel over [from, to) s, NaN where no sample lies.
double RawMean(const RecordedSamples& samples, const SensorChannel& c, double from_s, double to_s) {
  return samples.Mean(c.gyro ? c.axis : 3 + c.axis, from_s, to_s);
}

std::string SensorName(const SensorChannel& c) {
  return absl::StrFormat("%s %c", c.gyro ? "gyro" : "accelerometer", static_cast<char>('x' + c.axis));
}

// Two raw means and their change, with the decimals that show the change:
// a 0.6 mg step on a 964 mg reading needs two.
std::string RawChange(const SensorChannel& c, double before_si, double after_si, const char* before_label,
                      const char* after_label) {
  const ReadingUnit reading = UnitOf(c);
  const char* unit = reading.name;
  const double before = before_si * reading.per_si, after = after_si * reading.per_si, change = after - before;
  const int decimals =
      change != 0.0 ? std::clamp(1 - static_cast<int>(std::floor(std::log10(std::abs(change)))), 0, 6) : 1;
  return absl::StrFormat("its raw samples read %.*f %s %s and %.*f %s %s, a change of %.2g %s", decimals, before, unit,
                         before_label, decimals, after, unit, after_label, change, unit);
}

// One finding: what changed, when, how sure, and what the raw samples read.
std::string FindingLine(const EffectCandidate& c, const SensorChannel& channel, const RecordedSamples& run) {
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
  const double end_s = run.worked_on.samples.empty() ? onset_s : run.worked_on.samples.back().t_s;
  const double before = RawMean(run, channel, onset_s - kRawWindowS, onset_s);
  const double after = ramp ? RawMean(run, channel, end_s - kRawWindowS, end_s + 1.0)
                            : RawMean(run, channel, onset_s, onset_s + kRawWindowS);
  if (std::isfinite(before) && std::isfinite(after)) {
    line += "; " + RawChange(channel, before, after, "in the minute before",
                             ramp ? "in the run's last minute" : "in the minute after");
  }
  return line;
}

// Where the observations fail: the channels and the first interval's start.
struct Misfit {
  std::string channels;
  double first_s = 0.0;
  int intervals = 0;
};
Misfit MisfitOf(const AnalysisReport& r, bool gradual_only) {
  std::set<std::string> channels;
  Misfit m{"", std::numeric_limits<double>::infinity(), 0};
  for (const FaultInterval& f : r.faults) {
    if (gradual_only && f.kind != FaultKind::kGradual) continue;
    channels.insert(f.channel);
    m.first_s = std::min(m.first_s, f.start_s);
    ++m.intervals;
  }
  m.channels = absl::StrJoin(channels, ", ");
  return m;
}

// The channels whose own mean NIS lies outside its band, farthest first (at
// most three), as "lat (NIS 0.35), height (0.62)".
std::string ChannelsOutsideTheirBand(const AnalysisReport& r, double family_wise_alpha) {
  std::vector<const ChannelFit*> outside;
  for (const ChannelFit& c : r.channels) {
    if (c.count > 0 && c.nis_mean > 0.0 && MeanNisBandOf(c.count, family_wise_alpha).Excludes(c.nis_mean))
      outside.push_back(&c);
  }
  std::ranges::sort(outside, [](const ChannelFit* a, const ChannelFit* b) {
    return std::abs(std::log(a->nis_mean)) > std::abs(std::log(b->nis_mean));
  });
  if (outside.size() > 3) outside.resize(3);
  std::vector<std::string> parts;
  for (const ChannelFit* c : outside)
    parts.push_back(parts.empty() ? absl::StrFormat("%s (NIS %.2f)", c->name, c->nis_mean)
                                  : absl::StrFormat("%s (%.2f)", c->name, c->nis_mean));
  return absl::StrJoin(parts, ", ");
}

bool QuieterThanItsModel(const AnalysisReport& r) { return r.fit.nis_mean < r.nis_band_low; }

// Where the bench moved, how long in all, and by which channel's samples.
std::string BenchMotionLine(const AnalysisReport& r) {
  double moved_s = 0.0;
  const BenchMotion* largest = &r.bench_motion.front();
  for (const BenchMotion& m : r.bench_motion) {
    moved_s += m.end_s - m.start_s;
    if (m.statistic > largest->statistic) largest = &m;
  }
  return absl::StrFormat(
      "  the bench moved in %d stretch(es), %.0f s of %.0f s, the first at %.0f s (most at %.0f s, on %s): the "
      "updates there test the bench, not the unit, and are not held against it",
      static_cast<int>(r.bench_motion.size()), moved_s, r.duration_s, r.bench_motion.front().start_s,
      largest->start_s, kSensorChannelNames[static_cast<size_t>(largest->sensor_channel)]);
}

// The warm-ups the model carries (model_change.h, ExplainTheStartByWarmUps)
// whose start value the run determines (beyond 1.96 SE), the clearest three:
// what the unit does after power-up, which the verdict takes as the unit's
// own. Empty when there is none.
std::string SettlingLine(const AnalysisReport& r) {
  constexpr double kDetermined = 1.96;  // two-sided 95 %
  struct Settling {
    SensorChannel channel;
    double start_si, z, tau_s;
  };
  std::vector<Settling> settling;
  // The model names a warm-up with its time constant, "gyro_warm_up.x@516"
  // (ErrorModel::EffectNames); its start value is among the estimates.
  for (const std::string& effect : r.model_effects) {
    const auto terms = ParseEffectSelector(effect);
    const auto tau_s = ParseOnset(effect);
    if (!terms.ok() || terms->size() != 1 || terms->front().family->kind != EffectKind::kTransient ||
        !tau_s.ok() || !tau_s->has_value()) {
      continue;
    }
    const std::string name = terms->front().Name();
    const auto start = std::find_if(r.identified.begin(), r.identified.end(),
                                    [&](const ParameterEstimate& p) { return p.name == name; });
    SensorChannel channel;
    if (start == r.identified.end() || !ChannelOf(name, channel)) continue;
    const double z = std::abs(start->value / start->std_error);
    if (z > kDetermined) settling.push_back({channel, start->value, z, **tau_s});
  }
  if (settling.empty()) return "";
  std::sort(settling.begin(), settling.end(), [](const Settling& a, const Settling& b) { return a.z > b.z; });
  settling.resize(std::min<std::size_t>(settling.size(), kMaxFindings));
  std::vector<std::string> parts;
  for (const Settling& s : settling) {
    parts.push_back(absl::StrFormat("%s from %s with τ %.0f s", SensorName(s.channel), Reading(s.channel, s.start_si),
                                    s.tau_s));
  }
  return "  it settles after power-up, which its model carries: " + absl::StrJoin(parts, ", ");
}

// The drifts the run's data took over its specified values (a datasheet's,
// a unit type's): the last identification whose likelihood-ratio test
// rejected them at the family-wise level (a DRIFTS_IDENTIFIED decision
// adopted on the data; an Allan fit's values are no specification the unit
// departs from), and of its σ estimates the two
// farthest from their a-priori values whose 95 % intervals leave them out.
// A healthy unit's drifts pass that test, so a line here is the run's
// evidence, not a chance departure. Empty when there is none.
std::string DriftsLine(const AnalysisReport& r) {
  constexpr int kMostDrifts = 2;
  const Decision* taken = nullptr;
  for (const Decision& d : r.decisions) {
    if (d.kind == DecisionKind::kDriftsIdentified && d.adopted && !d.Qualified("allan_fit_prior")) taken = &d;
  }
  if (taken == nullptr) return "";
  std::vector<const ParameterEstimate*> departed;
  for (const ParameterEstimate& p : r.identified) {
    const bool tested = std::find(taken->subjects.begin(), taken->subjects.end(), p.name) != taken->subjects.end();
    if (!tested || !p.name.ends_with(".sigma") || !(p.a_priori > 0.0) || !(p.value > 0.0)) continue;
    if (p.ci95_low <= p.a_priori && p.a_priori <= p.ci95_high) continue;
    departed.push_back(&p);
  }
  if (departed.empty()) return "";
  const auto departure = [](const ParameterEstimate* p) { return std::abs(std::log(p->value / p->a_priori)); };
  std::sort(departed.begin(), departed.end(),
            [&](const ParameterEstimate* a, const ParameterEstimate* b) { return departure(a) > departure(b); });
  departed.resize(std::min<std::size_t>(departed.size(), kMostDrifts));
  std::vector<std::string> drifts;
  for (const ParameterEstimate* p : departed) {
    SensorChannel channel;
    if (!ChannelOf(p->name, channel)) continue;
    drifts.push_back(absl::StrFormat("%s drift σ %s against %s (%.2g ×)", SensorName(channel),
                                     Reading(channel, p->value), Reading(channel, p->a_priori),
                                     p->value / p->a_priori));
  }
  if (drifts.empty()) return "";
  return absl::StrFormat(
      "  its drifts are not its model's (2Δℓ %.1f against χ²(%d) at %.2g): %s; the diagnosis weighs them against "
      "the failure modes",
      taken->statistic, taken->degrees_of_freedom, taken->level, absl::StrJoin(drifts, ", "));
}

std::string VerdictLine(const AnalysisReport& r, int faults, double family_wise_alpha) {
  const std::string fit = absl::StrFormat("NIS %.3f, band %.3f–%.3f", r.fit.nis_mean, r.nis_band_low, r.nis_band_high);
  // FAULTY without a fault effect is the moving-window test's verdict: its
  // gradual intervals say where.
  const Misfit misfit = MisfitOf(r, /*gradual_only=*/r.verdict == Verdict::kFaulty);
  switch (r.verdict) {
    case Verdict::kGood:
      return absl::StrFormat("GOOD: the unit behaves as its error model says over %s (%s); no fault found.",
                             r.bench_motion.empty() ? "the whole run" : "the run where the bench was still", fit);
    case Verdict::kOperable:
      if (misfit.intervals == 0) {
        // No interval: the whole run's NIS is outside its band. Which way,
        // and where, tells a pessimistic model from a noisy bench.
        const std::string where = ChannelsOutsideTheirBand(r, family_wise_alpha);
        const std::string most = where.empty() ? "" : ", most on " + where;
        if (QuieterThanItsModel(r)) {
          return absl::StrFormat(
              "OPERABLE: no sensor fault stands; the run is quieter than its model (%s, below the band)%s: the "
              "test is less sensitive there than the unit allows.",
              fit, most);
        }
        return absl::StrFormat("OPERABLE: no sensor fault stands, but the run is noisier than its model (%s, above "
                               "the band)%s.",
                               fit, most);
      }
      return absl::StrFormat(
          "OPERABLE: no sensor fault stands, but the model misfits in %d interval(s) on %s, the first at %.0f s (%s).",
          misfit.intervals, misfit.channels, misfit.first_s, fit);
    case Verdict::kFaulty:
      if (faults > 0) return absl::StrFormat("FAULTY: %d sensor fault(s) found (%s):", faults, fit);
      return absl::StrFormat("FAULTY: the model fails gradually on %s from %.0f s (%s):", misfit.channels,
                             misfit.first_s, fit);
  }
  return "";
}

}  // namespace

double RecordedSamples::Mean(int channel, double from_s, double to_s) const {
  const double removed = channel < 3 ? removed_gyro_rad_s[channel] : removed_acc_mps2[channel - 3];
  double sum = 0.0;
  int n = 0;
  for (const ImuSample& s : worked_on.samples) {
    if (s.t_s < from_s || s.t_s >= to_s) continue;
    sum += SensorChannelValue(s, channel) + removed;
    ++n;
  }
  // A repaired spike was replaced before the constants were removed.
  for (const SampleOutlier& spike : repaired_spikes) {
    if (spike.sensor_channel == channel && spike.time_s >= from_s && spike.time_s < to_s)
      sum += spike.value - spike.replacement;
  }
  return n > 0 ? sum / n : std::nan("");
}

std::vector<std::string> PlainWordsVerdict(const AnalysisReport& report, const BenchRun& run,
                                           double family_wise_alpha) {
  return PlainWordsVerdict(report, RecordedSamples{run, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), {}},
                           family_wise_alpha);
}

std::vector<std::string> PlainWordsVerdict(const AnalysisReport& report, const RecordedSamples& run,
                                           double family_wise_alpha) {
  // Faults first: changes at an onset, one a sensor axis (a step and a ramp
  // on one axis are two readings of one change), the most significant.
  std::vector<std::string> findings;
  std::set<std::string> faulty_modules;
  std::vector<const EffectCandidate*> missing;
  for (const EffectCandidate& c : report.effect_candidates) {
    SensorChannel channel;
    if (!c.SignificantAt(family_wise_alpha) || !ChannelOf(c.name, channel)) continue;
    if (!c.onset_s.has_value()) {
      missing.push_back(&c);
      continue;
    }
    if (faulty_modules.count(SensorName(channel)) > 0 || static_cast<int>(findings.size()) == kMaxFindings) continue;
    findings.push_back("  " + FindingLine(c, channel, run));
    faulty_modules.insert(SensorName(channel));
  }
  const int faults = static_cast<int>(findings.size());
  // A gradual failure with no fault effect behind it: where the filter put it,
  // by the sensor's name where the state is one sensor axis'.
  if (faults == 0 && report.verdict == Verdict::kFaulty && !report.localisation.empty()) {
    const Localisation& l = report.localisation.front();
    SensorChannel channel;
    const std::string where = ChannelOf(l.state, channel)
                                  ? absl::StrFormat("the %s (%s)", SensorName(channel), l.state)
                                  : l.state;
    findings.push_back(absl::StrFormat("  the filter localises it to %s at %.0f s (p %.1g)", where, l.time_s,
                                       l.p_value));
  }
  // Then what the model lacks: constants the scan finds, which the loop adds.
  for (const EffectCandidate* c : missing) {
    if (static_cast<int>(findings.size()) == kMaxFindings) break;
    SensorChannel channel;
    ChannelOf(c->name, channel);
    findings.push_back("  " + FindingLine(*c, channel, run));
  }

  std::vector<std::string> lines = {VerdictLine(report, faults, family_wise_alpha)};
  // The verdict, its findings, how it settles after power-up, where the bench
  // moved, and what to do.
  const std::string settling = SettlingLine(report);
  const std::string drifts = DriftsLine(report);
  const std::size_t room = kPlainWordsMaxLines - 2 - (report.bench_motion.empty() ? 0 : 1) -
                           (settling.empty() ? 0 : 1) - (drifts.empty() ? 0 : 1);
  findings.resize(std::min(findings.size(), room));
  lines.insert(lines.end(), findings.begin(), findings.end());
  if (!drifts.empty()) lines.push_back(drifts);
  if (!settling.empty()) lines.push_back(settling);
  if (!report.bench_motion.empty()) lines.push_back(BenchMotionLine(report));
  std::string to_do;
  if (faults > 0) {
    to_do = absl::StrFormat("check the %s module%s (the change is in %s raw samples), then test again to confirm",
                            absl::StrJoin(faulty_modules, " and "), faulty_modules.size() > 1 ? "s" : "",
                            faulty_modules.size() > 1 ? "their" : "its");
  } else if (!missing.empty()) {
    to_do = absl::StrFormat("add %s to the model (insdiag analyze --add %s, or Add on the page) and see whether the "
                            "misfit goes",
                            missing.front()->name, missing.front()->name);
  } else if (report.verdict == Verdict::kFaulty) {
    to_do = "read where the model fails below, check the bench at those times, and test again";
  } else if (report.verdict == Verdict::kOperable && report.faults.empty() && QuieterThanItsModel(report)) {
    to_do = "nothing on the unit; its datasheet's noise figures, or a longer still run, would let the test be as "
            "sensitive as the unit allows";
  } else if (report.verdict == Verdict::kOperable && report.faults.empty()) {
    to_do = "check the bench for vibration or motion the reference does not record, and test again";
  } else if (report.verdict == Verdict::kOperable) {
    to_do = "check the bench at those times (a knock, motion, power), and test again if they recur";
  } else {
    to_do = "nothing; the unit passes";
  }
  lines.push_back("To do: " + to_do + ".");
  lines.resize(std::min<std::size_t>(lines.size(), kPlainWordsMaxLines));
  return lines;
}

}  // namespace insdiag::engine
