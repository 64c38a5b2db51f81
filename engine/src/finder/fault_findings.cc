#include "insdiag/engine/finder/fault_findings.h"

#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include "insdiag/engine/filter/linear_range.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine {
namespace {

std::string RawChannel(const EffectTerm& term) {
  return std::string(term.family->sensor == Sensor::kGyro ? "gyro_" : "acc_") +
         AxisLabel(AxisSet::kSingle, term.axis, term.axis);
}

}  // namespace

bool AreLookAlikes(const OnsetFit& a, const OnsetFit& b) {
  const auto names = [](const OnsetFit& f, const EffectTerm& t) {
    return std::ranges::find(f.ambiguous_with, t) != f.ambiguous_with.end();
  };
  return (a.term.family->sensor == b.term.family->sensor && a.term.axis == b.term.axis) ||
         names(a, b.term) || names(b, a.term);
}

const RawSampleChange* SeenInRawSamples(const OnsetFit& f,
                                        std::span<const RawSampleChange> raw_changes) {
  for (const RawSampleChange& r : raw_changes) {
    if (r.sensor == f.term.family->sensor && r.axis == f.term.axis &&
        r.shape == f.term.family->regressor && r.size * f.estimate > 0.0 &&
        std::abs(r.time_s - f.onset_s) <= 3.0 * f.onset_std_s + r.tolerance_s) {
      return &r;
    }
  }
  return nullptr;
}

std::vector<EffectCandidate> FaultCandidates(const std::vector<OnsetFit>& fits, int scalar_updates,
                                             const std::optional<FaultScale>& scale,
                                             std::span<const RawSampleChange> raw_changes) {
  std::vector<EffectCandidate> out;
  const double log_n = std::log(static_cast<double>(std::max(1, scalar_updates)));
  for (const OnsetFit& f : fits) {
    EffectCandidate c;
    c.name = f.term.Name();
    c.family = std::string(f.term.family->name);
    c.source = "GLR";
    c.unit = std::string(f.term.family->unit);
    c.dof = 2;
    c.identifiable = f.identifiable;
    if (!f.identifiable) {
      c.std_error = std::numeric_limits<double>::infinity();
      c.note = "not identifiable with this profile: the run leaves no onset with room on both sides, or its "
               "signature vanishes";
      out.push_back(std::move(c));
      continue;
    }
    // 2Δℓ is the linear model's; whether the fault is a finding counts the
    // first-order model's error of its magnitude beside its noise (linear_range.h).
    c.statistic = f.statistic;
    c.estimate = f.estimate;
    c.std_error =
        StandardErrorWithLinearisation(f.estimate, f.std_error, f.peak_attitude_error_rad);
    const double noise_share = f.std_error / c.std_error;
    c.p_value = noise_share == 1.0
                    ? f.p_value
                    : OnsetPValue(f.statistic * noise_share * noise_share, f.path_length);
    c.predicted_delta_aic = -c.statistic + 2.0 * c.dof;
    c.predicted_delta_bic = -c.statistic + c.dof * log_n;
    c.onset_s = f.onset_s;
    if (scale.has_value()) {
      const double sigma = scale->drift_sigma[static_cast<size_t>(
          SensorAxisIndex(f.term.family->sensor, f.term.axis))];
      const double change = f.term.family->regressor == Regressor::kRamp
                                ? std::abs(f.estimate) * std::max(0.0, scale->run_end_s - f.onset_s)
                                : std::abs(f.estimate);
      if (sigma > 0.0) c.size_in_drift_sigma = change / sigma;
    }
    c.onset_std_s = f.onset_std_s;
    c.onset_low_s = f.onset_low_s;
    c.onset_high_s = f.onset_high_s;
    c.note = absl::StrFormat("likelihood ratio over %d onsets: max 2Δℓ %.1f; onset %.0f s (±1σ %.0f–%.0f s)",
                             f.onsets_tried, f.statistic, f.onset_s, f.onset_low_s, f.onset_high_s);
    if (const RawSampleChange* raw = SeenInRawSamples(f, raw_changes); raw != nullptr) {
      c.seen_in_raw_samples = true;
      absl::StrAppend(
          &c.note,
          absl::StrFormat("; seen in the raw samples of a still segment: %s of %.3g %s at %.0f s",
                          raw->shape == Regressor::kRamp ? "a ramp" : "a jump", raw->size, c.unit,
                          raw->time_s));
    }
    const double relative_std_error = f.std_error / std::abs(f.estimate);
    const LinearRange range = LinearRangeOf(f.peak_attitude_error_rad, relative_std_error);
    // A fault far outside the range is reported so, not ranked (linear_range.h).
    if (range == LinearRange::kFarOutside) c.identifiable = false;
    if (range != LinearRange::kWithin) {
      c.note = absl::StrCat(LinearRangeNote(range, f.peak_attitude_error_rad, relative_std_error),
                            "; ", c.note);
    }
    out.push_back(std::move(c));
  }
  // A step and a ramp of one sensor axis whose 2Δℓ are within 2 of each
  // other (their parameter counts are equal) are not worth telling apart
  // (Kass & Raftery, JASA 90(430), 1995): each names the other. So do faults
  // whose signatures the scan found nearly parallel (onset_scan.h).
  for (size_t i = 0; i < out.size(); ++i) {
    for (size_t j = 0; j < out.size(); ++j) {
      const OnsetFit& a = fits[i];
      const OnsetFit& b = fits[j];
      if (i == j || !out[i].identifiable || !out[j].identifiable ||
          a.term.family->sensor != b.term.family->sensor || a.term.axis != b.term.axis ||
          a.term.family == b.term.family) {
        continue;
      }
      if (std::abs(a.statistic - b.statistic) < kIndistinguishableDeltaBic) out[i].correlated_with.push_back(out[j].name);
    }
    for (const EffectTerm& other : fits[i].ambiguous_with) {
      const auto named = std::ranges::find(out, other.Name(), &EffectCandidate::name);
      if (named != out.end() && !named->identifiable) continue;  // far outside the linear range
      if (std::ranges::find(out[i].correlated_with, other.Name()) == out[i].correlated_with.end()) {
        out[i].correlated_with.push_back(other.Name());
      }
    }
  }
  return out;
}

bool IsFaultSource(std::string_view source) { return source == "GLR" || source == "RAW"; }

bool IsFaultCandidate(const EffectCandidate& c) { return IsFaultSource(c.source); }

namespace {

// The least-squares slope's standard error over `span_s` after the onset
// (fault_findings.h, AddRawSampleFaultCandidates).
double RawSlopeStdError(const FaultScale& scale, int sensor_axis, double span_s) {
  const auto i = static_cast<size_t>(sensor_axis);
  const double white = scale.white_noise_density[i];
  const double walk = scale.drift_tau_s[i] > 0.0
                          ? scale.drift_sigma[i] * std::sqrt(2.0 / scale.drift_tau_s[i])
                          : 0.0;
  return std::sqrt(12.0 * white * white / (span_s * span_s * span_s) + 1.2 * walk * walk / span_s);
}

// Two measurements of one fault at one onset: the raw samples' and the
// navigation errors'. Where the navigation errors measure it to within the
// first-order model's range (linear_range.h, at the raw estimate's size) and
// the two differ beyond their joint standard error at the family-wise level,
// the raw samples' change is not the sensor's (a bench's periodic motion
// moves the raw curve's tests; the navigation errors integrate it away).
// What the note says then; nullopt where they agree or cannot be compared.
std::optional<std::string> NavigationErrorsRefute(const OnsetFit& fit, const EpochRun& run,
                                                  const RawSampleChange& change, const EffectCandidate& raw,
                                                  double family_wise_alpha) {
  const auto nav = EstimateNearOnset(fit, run, change.time_s, std::max(change.tolerance_s, run.update_interval_s));
  if (!nav.has_value() || !(nav->std_error > 0.0) || !(raw.std_error > 0.0) || fit.estimate == 0.0) {
    return std::nullopt;
  }
  // The attitude error the raw estimate would give, from the scan's response per unit of fault.
  const double peak_attitude_error_rad = fit.peak_attitude_error_rad / std::abs(fit.estimate) * std::abs(raw.estimate);
  const double nav_std_error = StandardErrorWithLinearisation(raw.estimate, nav->std_error, peak_attitude_error_rad);
  const double difference = raw.estimate - nav->estimate;
  const double z2 = difference * difference / (raw.std_error * raw.std_error + nav_std_error * nav_std_error);
  if (!(stats::ChiSquareSurvival(z2, 1) < family_wise_alpha)) return std::nullopt;
  return absl::StrFormat(
      "refuted by the navigation errors: from %.0f s they give %.3g ± %.2g %s against the raw samples' %.3g ± %.2g",
      nav->onset_s, nav->estimate, nav_std_error, raw.unit, raw.estimate, raw.std_error);
}

}  // namespace

void AddRawSampleFaultCandidates(std::vector<EffectCandidate>& candidates,
                                 const std::vector<OnsetFit>& fits,
                                 std::span<const RawSampleChange> raw_changes, const EpochRun& run,
                                 int scalar_updates, const FaultScale& scale,
                                 double family_wise_alpha) {
  const double log_n = std::log(static_cast<double>(std::max(1, scalar_updates)));
  for (const RawSampleChange& raw : raw_changes) {
    if (!(raw.p_value < 1.0)) continue;
    const auto fit = std::ranges::find_if(fits, [&](const OnsetFit& f) {
      return f.term.family->sensor == raw.sensor && f.term.axis == raw.axis &&
             f.term.family->regressor == raw.shape;
    });
    if (fit == fits.end()) continue;  // the model holds the fault already
    const std::string name = fit->term.Name();
    const double span_s = scale.run_end_s - raw.time_s;
    if (!(span_s > 0.0)) continue;
    const bool ramp = raw.shape == Regressor::kRamp;
    const double std_error = ramp ? RawSlopeStdError(scale, SensorAxisIndex(raw.sensor, raw.axis), span_s)
                                  : raw.std_error;
    // The change is a finding where the curve's shape and its measured size
    // are both significant: an intersection–union test, whose p is the
    // larger of the two (Berger, Technometrics 24(4), 1982).
    const double size_z = std_error > 0.0 ? raw.size / std_error : 0.0;
    const double p_value = std::max(std::min(1.0, raw.p_value * static_cast<double>(kSensorAxisCount)),
                                    stats::ChiSquareSurvival(size_z * size_z, 1));
    // The scan's fit stands where it is the stronger evidence, or a finding
    // that places the samples' change: over the whole run it places the onset
    // better.
    const auto scanned = std::ranges::find(candidates, name, &EffectCandidate::name);
    if (scanned != candidates.end() &&
        (scanned->p_value <= p_value ||
         (scanned->seen_in_raw_samples && scanned->p_value < family_wise_alpha))) {
      continue;
    }
    EffectCandidate c;
    c.name = name;
    c.family = std::string(fit->term.family->name);
    c.source = "RAW";
    c.unit = std::string(fit->term.family->unit);
    c.dof = 1;
    c.estimate = raw.size;
    c.std_error = std_error;
    c.p_value = p_value;
    c.statistic = StatisticWithOnsetAt(*fit, run, raw.time_s).value_or(0.0);
    c.predicted_delta_aic = -c.statistic + 2.0;
    c.predicted_delta_bic = -c.statistic + log_n;
    c.onset_s = raw.time_s;
    c.onset_std_s = raw.tolerance_s;
    c.onset_low_s = raw.time_s - raw.tolerance_s;
    c.onset_high_s = raw.time_s + raw.tolerance_s;
    c.seen_in_raw_samples = true;
    const double sigma =
        scale.drift_sigma[static_cast<size_t>(SensorAxisIndex(raw.sensor, raw.axis))];
    if (sigma > 0.0) c.size_in_drift_sigma = std::abs(raw.size) * (ramp ? span_s : 1.0) / sigma;
    c.note = absl::StrFormat(
        "%s the still segments' raw samples show %s %.0f s (p %.2g: the %s test over the six "
        "channels, and its size); the navigation errors give it 2Δℓ %.1f at that onset",
        ramp ? "a ramp" : "a jump", ramp ? "from" : "at", raw.time_s, c.p_value, ramp ? "ramp" : "jump",
        c.statistic);
    if (const auto refuted = NavigationErrorsRefute(*fit, run, raw, c, family_wise_alpha)) {
      c.identifiable = false;
      c.note = *refuted + "; " + c.note;
    }
    if (scanned != candidates.end()) {
      c.correlated_with = scanned->correlated_with;
      *scanned = std::move(c);
    } else {
      candidates.push_back(std::move(c));
    }
  }
}

bool IsLikelierLookAlike(const EffectCandidate& a, const EffectCandidate& b, double alpha) {
  const bool look_alikes =
      IsFaultCandidate(a) && IsFaultCandidate(b) && a.SignificantAt(alpha) &&
      b.SignificantAt(alpha) &&
      std::abs(a.predicted_delta_bic - b.predicted_delta_bic) < kIndistinguishableDeltaBic &&
      std::ranges::find(a.correlated_with, b.name) != a.correlated_with.end();
  if (!look_alikes) return false;
  if (a.seen_in_raw_samples != b.seen_in_raw_samples) return b.seen_in_raw_samples;
  return a.size_in_drift_sigma.has_value() && b.size_in_drift_sigma.has_value() &&
         *b.size_in_drift_sigma < *a.size_in_drift_sigma;
}

void PutLikelierLookAlikesFirst(std::vector<EffectCandidate>& ranked, double alpha) {
  for (size_t i = 0; i < ranked.size(); ++i) {
    // Each move puts a strictly likelier fault at i (seen in the raw samples,
    // then smaller), so this ends.
    for (size_t j = i + 1; j < ranked.size(); ++j) {
      if (!IsLikelierLookAlike(ranked[i], ranked[j], alpha)) continue;
      std::rotate(ranked.begin() + static_cast<std::ptrdiff_t>(i),
                  ranked.begin() + static_cast<std::ptrdiff_t>(j),
                  ranked.begin() + static_cast<std::ptrdiff_t>(j) + 1);
      j = i;
    }
  }
}

std::vector<FaultFinding> SignificantFaults(const std::vector<EffectCandidate>& candidates, double alpha) {
  double best_other_bic = std::numeric_limits<double>::infinity();
  for (const EffectCandidate& c : candidates) {
    if (!IsFaultCandidate(c) && c.SignificantAt(alpha)) {
      best_other_bic = std::min(best_other_bic, c.predicted_delta_bic);
    }
  }
  std::vector<EffectCandidate> by_bic;
  for (const EffectCandidate& c : candidates) {
    if (IsFaultCandidate(c) && c.SignificantAt(alpha) && c.onset_s.has_value() &&
        c.predicted_delta_bic < best_other_bic) {
      by_bic.push_back(c);
    }
  }
  std::stable_sort(by_bic.begin(), by_bic.end(),
                   [](const EffectCandidate& a, const EffectCandidate& b) {
                     return a.predicted_delta_bic < b.predicted_delta_bic;
                   });
  // Of look-alikes the run cannot tell apart, the likelier stands for them.
  PutLikelierLookAlikesFirst(by_bic, alpha);
  std::vector<FaultFinding> out;
  std::vector<const EffectCandidate*> taken;
  for (const EffectCandidate& c : by_bic) {
    // Faults the run cannot tell apart are explanations of one failure.
    const auto alike = [&](const EffectCandidate* t) {
      return std::ranges::find(t->correlated_with, c.name) != t->correlated_with.end() ||
             std::ranges::find(c.correlated_with, t->name) != c.correlated_with.end();
    };
    if (std::any_of(taken.begin(), taken.end(), alike)) continue;
    taken.push_back(&c);
    const auto terms = ParseEffectSelector(c.name);
    if (!terms.ok() || terms->size() != 1) continue;
    // One fault per sensor axis: a step and a ramp on the same axis are two
    // explanations of one failure; the lower ΔBIC stands.
    const EffectTerm& term = terms->front();
    const auto same_axis = [&](const FaultFinding& f) {
      return f.term.family->sensor == term.family->sensor && f.term.axis == term.axis;
    };
    if (std::any_of(out.begin(), out.end(), same_axis)) continue;
    out.push_back(
        {term, *c.onset_s, c.statistic, c.p_value_holm, c.estimate, c.std_error, c.source});
  }
  return out;
}

std::optional<FaultFinding> FaultInModel(const EffectTerm& term, double onset_s, double estimate, double std_error,
                                         double alpha) {
  if (!(std_error > 0.0) || !std::isfinite(std_error)) return std::nullopt;
  const double z = estimate / std_error;
  const double p = stats::ChiSquareSurvival(z * z, 1);
  if (!(p < alpha)) return std::nullopt;
  return FaultFinding{term, onset_s, z * z, p, estimate, std_error};
}

void ReportFaults(const std::vector<FaultFinding>& findings, double run_end_s, AnalysisReport& report) {
  for (const FaultFinding& f : findings) {
    report.verdict = Verdict::kFaulty;
    FaultInterval interval;
    interval.channel = RawChannel(f.term);
    interval.start_s = f.onset_s;
    interval.end_s = run_end_s;
    interval.kind = f.term.family->regressor == Regressor::kStep ? FaultKind::kAbrupt : FaultKind::kGradual;
    interval.peak_statistic = f.statistic;
    report.faults.push_back(interval);
    Localisation where;
    where.state = f.term.Name();
    where.time_s = f.onset_s;
    where.statistic = f.statistic;
    where.p_value = f.p_value;
    where.method = f.method;
    where.jump = f.estimate;
    where.jump_std_error = f.std_error;
    report.localisation.push_back(where);
  }
  std::stable_sort(report.faults.begin(), report.faults.end(),
                   [](const FaultInterval& a, const FaultInterval& b) { return a.start_s < b.start_s; });
}

}  // namespace insdiag::engine
