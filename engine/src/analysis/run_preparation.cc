// The run's preparation (analysis/prepared_run.h): the samples screened,
// the a-priori model chosen, the Allan analysis, the dominant constants
// removed, and the run condensed with the baseline effects in its pilot.
#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include "analysis/prepared_run.h"
#include "analysis/run_context.h"
#include "analysis/steps_in_raw_samples.h"
#include "insdiag/engine/analysis.h"
#include "insdiag/engine/nav/reference_readout.h"
#include "insdiag/engine/numerics/parallel_map.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine {
namespace {

using pipeline::Progress;

// The dominant constant biases removed from `run` (ident/static_constants.h),
// on the Allan analysis's static segments when it ran.
ident::RemovedConstants RemoveDominantConstants(BenchRun& run, const std::optional<ident::AllanResult>& allan,
                                                const pipeline::APriori& a_priori, const AnalysisOptions& options,
                                                DecisionLog& decisions) {
  const ident::ConstantPrior prior = a_priori.FromAllanFit() ? ident::ConstantPrior::kNone
                                                         : ident::ConstantPrior::kBoundedByDrift;
  std::vector<std::string> notes;
  ident::RemovedConstants removed;
  if (allan.has_value()) {
    removed = ident::RemoveDominantConstants(run, allan->segments, a_priori.model, options.dominant_constants, prior,
                                             notes);
  } else if (auto segments = ident::FindStaticSegments(run, options.allan); segments.ok()) {
    removed = ident::RemoveDominantConstants(run, *segments, a_priori.model, options.dominant_constants, prior, notes);
  }
  decisions.NoteEach(notes);
  return removed;
}

// The Allan analysis of the run's static segments, when identification runs.
std::optional<ident::AllanResult> AllanOfStaticSegments(const BenchRun& run, const AnalysisOptions& options,
                                                        DecisionLog& decisions) {
  if (!options.identify) return std::nullopt;
  auto allan = ident::AllanAnalysis(run, options.allan);
  if (allan.ok()) {
    for (const ident::AllanChannel& ch : allan->channels) {
      for (const ident::RateJump& j : ch.jumps) {
        decisions.Note(
            absl::StrFormat("the Allan analysis cut %s's static segment at %.1f s, where its "
                            "rate's mean jumps by %.3g %s (z %.1f): "
                            "a step is not noise, and the curve leaves it out",
                            ch.name, j.time_s, j.size, ch.unit, j.z));
      }
      if (ch.ramp_evidence.has_value() && !ch.ramps.empty()) {
        const ident::RateRamp& ramp = ch.ramps.front();
        decisions.Note(absl::StrFormat(
            "the Allan analysis took a ramp out of %s's static segments: its Allan variance at "
            "τ %.0f s is %.3g times its Hadamard variance (z %.1f), which no noise of the model "
            "exceeds twice; the rate ramps by %.3g %s/s from %.1f s",
            ch.name, ch.ramp_evidence->tau_s, ch.ramp_evidence->avar_over_hvar, ch.ramp_evidence->z,
            ramp.slope, ch.unit, ramp.onset_s));
      }
    }
    return *std::move(allan);
  }
  decisions.Note("no Allan analysis: " + std::string(allan.status().message()));
  return std::nullopt;
}

// What the static segments' raw samples show (finder/raw_sample_evidence.h):
// the jumps and ramps the Allan analysis found, placed to a jump's window and
// to a segment's shortest length for a ramp (the least-squares onset of a
// ramp in noise is looser than a jump's); and each sensor axis' constant bias
// over the still samples of `run` as the analysis filters it.
// An accelerometer's jump less the specific-force change the gyros account
// for: a unit whose bench settles or is knocked turns by δθ, and its
// reading of gravity changes by Δf = −δθ × f̄ (the small-angle rotation of a
// fixed vector in body axes; Titterton & Weston, §3.6), a change of the
// samples but not of the sensor. δθ is the gyros' rate less its mean over the
// static segment (Earth's rate and the biases), integrated, between the means over the
// jump's two windows. Where the gyros resolve a turn, the remainder is
// tested as the jump was (allan.h, Jumps: J positions at 2Φ(−z) each), its
// standard error widened by the gyros' angle random walk over a window.
// A turn counts when the gyros resolve it: beyond three standard errors of
// their angle noise over a window (a one-sided chance of 0.13 % that noise
// alone reaches it).
constexpr double kResolvedTurnStdErrors = 3.0;

RawSampleChange UntiltedJump(const BenchRun& run, const ident::AllanResult& allan, const ident::AllanChannel& channel,
                             const ident::RateJump& jump, const ErrorModel& a_priori) {
  const double tau0_s = allan.tau0_s;
  RawSampleChange change{channel.sensor, channel.axis, Regressor::kStep, jump.time_s, jump.size,
                         static_cast<double>(jump.window) * tau0_s, jump.p_value,
                         jump.z > 0.0 ? std::abs(jump.size) / jump.z : 0.0};
  if (channel.sensor != Sensor::kAccelerometer || run.samples.empty() || !(jump.z > 0.0)) return change;
  const std::size_t k = pipeline::FirstSampleAfter(run, jump.time_s);
  const auto w = static_cast<std::size_t>(jump.window);
  const auto segment = std::find_if(allan.segments.begin(), allan.segments.end(), [&](const ident::StaticSegment& s) {
    return s.first_sample + w <= k && k + w <= s.end_sample;
  });
  if (segment == allan.segments.end()) return change;
  const pipeline::RawWindows windows = pipeline::RawWindowsAcross(
      run, k, w, pipeline::MeanGyroRate(run, segment->first_sample, segment->end_sample), tau0_s);
  const Eigen::Vector3d tilt_change = windows.TiltChange();
  const double n = static_cast<double>(w);
  double arw = 0.0;
  for (int a = 0; a < 3; ++a) arw = std::max(arw, a_priori.gyro.white_noise_density[a]);
  const double angle_noise_rad = arw * std::sqrt(n * tau0_s);
  const double tilt_noise = angle_noise_rad * windows.force_before.norm();
  // A turn the gyros do not resolve explains nothing: the jump stands as
  // the samples show it.
  if (std::abs(tilt_change[channel.axis]) < kResolvedTurnStdErrors * tilt_noise) return change;
  const double std_error = std::hypot(change.std_error, tilt_noise);
  const double remainder = jump.size - tilt_change[channel.axis];
  const double positions = jump.p_value / (2.0 * stats::NormalCdf(-jump.z));
  change.size = remainder;
  change.std_error = std_error;
  change.p_value = std::min(1.0, positions * 2.0 * stats::NormalCdf(-std::abs(remainder) / std_error));
  return change;
}

RawSampleEvidence RawSampleEvidenceOf(const BenchRun& run,
                                      const std::optional<ident::AllanResult>& allan,
                                      const ErrorModel& a_priori, const AnalysisOptions& options) {
  RawSampleEvidence out;
  if (!allan.has_value()) return out;
  for (const ident::StaticSegment& s : allan->segments) out.still.push_back({s.first_sample, s.end_sample});
  out.sample_interval_s = allan->tau0_s;
  for (const ident::AllanChannel& ch : allan->channels) {
    for (const ident::RateJump& j : ch.jumps) out.changes.push_back(UntiltedJump(run, *allan, ch, j, a_priori));
    for (const ident::RateRamp& r : ch.ramps) {
      out.changes.push_back({ch.sensor, ch.axis, Regressor::kRamp, r.onset_s, r.slope,
                             options.allan.min_segment_s,
                             ch.ramp_evidence.has_value() ? ch.ramp_evidence->p_value : 1.0});
    }
  }
  const auto constants =
      ident::MeasureStaticConstants(run, allan->segments, a_priori, options.dominant_constants);
  if (constants.ok()) {
    for (const ident::StaticConstant& c : constants->axes) {
      out.constants.push_back({c.term.family->sensor, c.term.axis, c.bias, c.std_error});
    }
  }
  return out;
}

// The unit type's nominal model's departure from the run's Allan deviation
// when it is beyond the drift search's reach: some channel's curve lies,
// beyond its confidence interval at the analysis's family-wise level, further
// from the model's curve than the widest σ factors the search starts from. Identification climbs from its
// starts and cannot reach a unit that far from them (a MEMS unit labelled
// with a navigation-grade type is 1000 times its drift).
std::optional<ident::AllanDeparture> DepartureBeyondSearch(const ident::AllanResult& allan,
                                                           const ErrorModel& nominal,
                                                           const ident::DriftStartOptions& starts,
                                                           double family_wise_alpha) {
  const auto [lowest, highest] = std::ranges::minmax(starts.grid_sigma_factors);
  std::optional<ident::AllanDeparture> farthest;
  for (const ident::AllanDeparture& d :
       ident::AllanDeparturesFrom(allan, nominal, family_wise_alpha)) {
    if (d.ratio >= lowest && d.ratio <= highest) continue;
    if (!farthest.has_value() || d.LogDistance() > farthest->LogDistance()) farthest = d;
  }
  return farthest;
}

// The drifts the static segments' Allan curve gives, where it gives a model.
std::optional<std::array<GaussMarkov, DriftAxis::kCount>> DriftsOfTheAllanFit(
    const ident::AllanResult& allan, const ReferenceAccuracy& reference) {
  auto fitted = ident::ErrorModelFromAllan(allan, reference);
  if (!fitted.ok()) return std::nullopt;
  std::array<GaussMarkov, DriftAxis::kCount> drifts;
  for (const DriftAxis d : DriftAxis::All())
    drifts[static_cast<std::size_t>(d.Index())] = DriftOf(*fitted, d);
  return drifts;
}

// Puts back the samples the screening took for spikes where the bench moved
// (FindBenchMotion), and drops them from the spikes.
void KeepTheMotionAsRecorded(SampleScreening& screening, BenchRun& run) {
  std::erase_if(screening.spikes, [&](const SampleOutlier& s) {
    if (!BenchMovedAt(screening.bench_motion, s.time_s)) return false;
    SensorChannelValue(run.samples[s.sample], s.sensor_channel) = s.value;
    return true;
  });
}

// Each axis' counted output quantum the static segments' samples lie on (0
// where they lie on none), whichever a-priori model the run takes.
std::array<double, DriftAxis::kCount> CountedQuantisationOf(const std::optional<ident::AllanResult>& allan) {
  std::array<double, DriftAxis::kCount> counted{};
  if (!allan.has_value()) return counted;
  for (const ident::AllanChannel& ch : allan->channels)
    counted[static_cast<size_t>(DriftAxis{ch.sensor, ch.axis}.Index())] = ch.CountedQuantisation();
  return counted;
}

// The a-priori model: the datasheet; else the unit type's nominal model,
// unless the run's Allan deviation puts the unit beyond the drift search's
// reach from it; else the Allan fit. The Allan analysis, which `allan`
// receives, runs here whenever the datasheet is incomplete. Drift
// identification searches decades from a class prior (a nominal model or
// an Allan fit); a datasheet's drifts are the unit's own specification, and
// a unit far from it shows as a re-tuned drift or as effects near it.
absl::StatusOr<pipeline::APriori> ChooseAPrioriModel(const BenchRun& run, const AnalysisRequest& request,
                                                     std::optional<ident::AllanResult>& allan,
                                                     const AnalysisOptions& options, DecisionLog& decisions) {
  pipeline::APriori out;
  out.drift_starts = options.drift_starts;
  auto model = APrioriModel(run, request.nominal, options.reference);
  if (const Datasheet& d = run.metadata.datasheet; d.gyro_bias_sigma_rad_s && d.gyro_bias_tau_s &&
                                                   d.acc_bias_sigma_mps2 && d.acc_bias_tau_s &&
                                                   model.ok()) {
    out.drift_starts.grid_tau_points = 0;
    out.source = pipeline::APrioriSource::kDatasheet;
    out.model = *std::move(model);
    pipeline::RecordAPrioriSource(decisions, "datasheet");
    return out;
  }
  allan = AllanOfStaticSegments(run, options, decisions);
  if (model.ok()) {
    const auto beyond = allan.has_value() ? DepartureBeyondSearch(*allan, *model, out.drift_starts,
                                                                  options.monitor.family_wise_alpha)
                                          : std::nullopt;
    if (!beyond.has_value()) {
      if (allan.has_value())
        out.drift_starts.raw_sample_drifts = DriftsOfTheAllanFit(*allan, model->reference);
      out.model = *std::move(model);
      pipeline::RecordAPrioriSource(decisions, "nominal");
      return out;
    }
    Decision set_aside;
    set_aside.kind = DecisionKind::kUnitTypeSetAside;
    set_aside.subjects = {beyond->channel};
    set_aside.level = options.monitor.family_wise_alpha;
    set_aside.adopted = true;
    set_aside.rejected = {{"unit type's nominal model", beyond->ratio}};
    set_aside.measures = {{"tau_s", beyond->tau_s}, {"ratio", beyond->ratio}};
    decisions.Record(std::move(set_aside));
  } else if (!allan.has_value()) {
    // Neither source: say why the run's own noise could not stand in.
    return absl::Status(model.status().code(),
                        absl::StrCat(model.status().message(), "; nor can the run's own Allan deviation stand in (",
                                     decisions.empty() ? "" : decisions.notes().back(), ")"));
  }
  const ReferenceAccuracy& reference = model.ok() ? model->reference : options.reference;
  std::vector<std::string> allan_fit_notes;
  auto from_allan = ident::ErrorModelFromAllan(*allan, reference, &allan_fit_notes);
  decisions.NoteEach(allan_fit_notes);
  if (!from_allan.ok()) return from_allan.status();
  out.model = *std::move(from_allan);
  out.source = pipeline::APrioriSource::kAllanFit;
  pipeline::RecordAPrioriSource(decisions, "allan_fit", model.ok() ? "" : "no_specification");
  return out;
}

// The options with the update interval this run is filtered at
// (UpdateIntervalForRun), and a note where it is not the one asked for.
AnalysisOptions WithTheRunsUpdateInterval(const AnalysisOptions& requested, const BenchRun& run,
                                          DecisionLog& decisions) {
  AnalysisOptions out = requested;
  const double sample_interval_s = run.NominalIntervalS();
  out.filter.update_interval_s =
      UpdateIntervalForRun(requested.filter.update_interval_s, sample_interval_s);
  if (out.filter.update_interval_s != requested.filter.update_interval_s) {
    decisions.Note(
        absl::StrFormat("updates every %.3g s (two samples) for the %.3g s asked: "
                        "with one sample an update interval, the position and velocity innovations "
                        "are multiples of one another and the six channels carry three dimensions",
                        out.filter.update_interval_s, requested.filter.update_interval_s));
  }
  return out;
}

// The encoders' readout noise, unless the model states it: the attitude
// channels' noise, and what "the table stands still" tolerates (epoch_run.h).
void MeasureAttitudeReadout(const BenchRun& run, ErrorModel& model, DecisionLog& decisions) {
  if (!run.ReferenceAttitudeIsRead() || model.reference.attitude_readout_sigma_rad > 0.0) return;
  model.reference.attitude_readout_sigma_rad = nav::AttitudeReadoutNoiseRad(run);
  if (model.reference.attitude_readout_sigma_rad > 0.0) {
    decisions.Note(absl::StrFormat(
        "the table's encoders read the attitude with a noise of %.3g rad (from the reference's second differences)",
        model.reference.attitude_readout_sigma_rad));
  }
}

// What the filter starts from where the run says its heading was not
// surveyed (bench_run.h): the user reads why the horizontal gyros' constant
// terms come with the heading's uncertainty.
void NoteUnsurveyedHeading(const BenchRun& run, const ErrorModel& model, DecisionLog& decisions) {
  if (run.metadata.AttitudeAccuracy().heading_surveyed) return;
  decisions.Note(absl::StrFormat(
      "the bench did not survey the heading: the filter starts it with σ %.3g rad, as gyro-compassing the start "
      "leaves it with this model's drifts (at most %.3g rad); at rest a heading error reads as a horizontal gyro bias "
      "of up to Ω cos L, so those two are told apart only where the table turns",
      UnsurveyedHeadingSigmaRad(model, run.metadata.site), kUnsurveyedHeadingLimitRad));
}

}  // namespace

namespace pipeline {

void RecordAPrioriSource(DecisionLog& decisions, std::string source, std::string why) {
  Decision d;
  d.kind = DecisionKind::kAPrioriModel;
  d.adopted = true;
  d.qualifiers.push_back(std::move(source));
  if (!why.empty()) d.qualifiers.push_back(std::move(why));
  decisions.Record(std::move(d));
}

namespace {

// The condensation's pilot: the a-priori model with the request's baseline effects.
absl::StatusOr<ErrorModel> PilotModel(const ScreenedRun& s, const AnalysisRequest& request) {
  ErrorModel base = s.a_priori.model;
  if (auto st = AddEffects(s.run, request.baseline_effects, s.options.filter.update_interval_s,
                           s.options.diffuse_prior_scale, base);
      !st.ok()) {
    return st;
  }
  return base;
}

}  // namespace

std::size_t ScreenedRun::Bytes() const {
  return run.samples.size() * (sizeof(ImuSample) + sizeof(reference_measurements[0]));
}

std::size_t PreparedRun::EpochBytes() const {
  return static_cast<std::size_t>(epochs.BytesPerEpoch() * epochs.size());
}

absl::StatusOr<std::unique_ptr<PreparedRun>> PrepareRun(BenchRun&& input, const AnalysisRequest& request,
                                                        const AnalysisOptions& requested_options) {
  if (auto st = requested_options.Validate(); !st.ok()) return st;
  if (input.samples.size() < 2) return absl::InvalidArgumentError("the run has fewer than two samples");
  auto screened = std::make_shared<ScreenedRun>();
  ScreenedRun& s = *screened;
  DecisionLog& decisions = s.decisions;
  s.options = WithTheRunsUpdateInterval(requested_options, input, decisions);
  const AnalysisOptions& options = s.options;

  Progress(options, 0.0, "screening samples");
  // The samples are screened and their dominant constants removed in place:
  // the report quotes them as recorded through RecordedSamples.
  s.run = std::move(input);
  BenchRun& run = s.run;
  // The table's motion within each sample: the screen and the condensation
  // both need it, and it depends on the reference alone (screening and the
  // constants removed below change the sensors' samples only).
  const nav::RunCompensations compensations(run);
  s.reference_measurements = ReferenceMeasurements(run, compensations);
  // The bench's motion from the samples with their spikes repaired: a
  // transmission error is one sample, a move many. A departure inside a
  // stretch where the bench moved is the motion itself: it is kept as
  // recorded, for the mechanisation to follow.
  SampleScreening& screening = s.screening;
  screening.spikes = ScreenAndRepairSpikes(run, s.reference_measurements, options.screening);
  screening.bench_motion = FindBenchMotion(run, s.reference_measurements, options.filter.update_interval_s,
                                           options.monitor.family_wise_alpha);
  KeepTheMotionAsRecorded(screening, run);

  Progress(options, 0.05, "Allan deviation and the run condensed to its epochs");
  auto a_priori = ChooseAPrioriModel(run, request, s.allan, options, decisions);
  if (!a_priori.ok()) return a_priori.status();
  s.a_priori = *std::move(a_priori);
  MeasureAttitudeReadout(run, s.a_priori.model, decisions);
  NoteUnsurveyedHeading(run, s.a_priori.model, decisions);
  if (options.remove_dominant_constants) {
    s.removed_constants = RemoveDominantConstants(run, s.allan, s.a_priori, options, decisions);
  }
  auto prepared = std::make_unique<PreparedRun>();
  auto base = PilotModel(s, request);
  if (!base.ok()) return base.status();
  prepared->base = *std::move(base);

  // The run condensed to its update epochs once: every pass below filters the
  // epochs. Beside it, the Allan analysis, where the a-priori model did not
  // need it first: identification and the report take it (the dominant
  // constants removed leave an Allan deviation as it was).
  absl::StatusOr<EpochRun> epochs;
  DecisionLog allan_notes;
  numerics::InParallel(
      [&] { epochs = CondenseRun(run, prepared->base, options.filter.update_interval_s, &compensations); },
      [&] {
        if (s.a_priori.FromDatasheet()) s.allan = AllanOfStaticSegments(run, options, allan_notes);
      });
  decisions.Append(allan_notes);
  if (!epochs.ok()) return epochs.status();
  prepared->epochs = *std::move(epochs);
  s.a_priori.counted_quantisation = CountedQuantisationOf(s.allan);
  s.raw_samples = RawSampleEvidenceOf(run, s.allan, s.a_priori.model, options);
  s.drift_ceilings = s.allan.has_value()
                         ? ident::DriftCeilings::FromAllan(*s.allan, options.monitor.family_wise_alpha)
                         : ident::DriftCeilings{};
  s.options.progress = nullptr;
  prepared->screened = std::move(screened);
  return prepared;
}

absl::StatusOr<std::unique_ptr<PreparedRun>> PrepareRun(std::shared_ptr<const ScreenedRun> screened,
                                                        const AnalysisRequest& request) {
  auto prepared = std::make_unique<PreparedRun>();
  auto base = PilotModel(*screened, request);
  if (!base.ok()) return base.status();
  prepared->base = *std::move(base);
  const BenchRun& run = screened->run;
  const nav::RunCompensations compensations(run);
  auto epochs = CondenseRun(run, prepared->base, screened->options.filter.update_interval_s, &compensations);
  if (!epochs.ok()) return epochs.status();
  prepared->epochs = *std::move(epochs);
  prepared->screened = std::move(screened);
  return prepared;
}

}  // namespace pipeline
}  // namespace insdiag::engine
