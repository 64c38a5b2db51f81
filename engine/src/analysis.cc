// The analysis as a pipeline of stages (analysis.h): each stage's inputs and
// outputs are explicit; the stages live in engine/src/analysis/.
#include "insdiag/engine/analysis.h"

#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include "analysis/identification.h"
#include "analysis/missing_effects.h"
#include "analysis/model_change.h"
#include "analysis/model_pass.h"
#include "analysis/prepared_run.h"
#include "analysis/run_context.h"
#include "analysis/steps_in_raw_samples.h"
#include "insdiag/engine/nav/reference_readout.h"
#include "insdiag/engine/numerics/parallel_map.h"
#include "insdiag/engine/plain_words.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine {
absl::Status AnalysisOptions::Validate() const {
  if (auto st = filter.Validate(); !st.ok()) return st;
  if (!(monitor.window_s > 0.0)) return absl::InvalidArgumentError("monitor window must be positive");
  if (!(monitor.family_wise_alpha > 0.0 && monitor.family_wise_alpha < 1.0)) {
    return absl::InvalidArgumentError("family-wise α must be in (0, 1)");
  }
  if (!(diffuse_prior_scale > 0.0)) return absl::InvalidArgumentError("diffuse prior scale must be positive");
  return absl::OkStatus();
}

absl::StatusOr<ErrorModel> APrioriModel(const BenchRun& run, const std::optional<ErrorModel>& nominal,
                                        const ReferenceAccuracy& reference) {
  const Datasheet& d = run.metadata.datasheet;
  ErrorModel model = nominal.value_or(ErrorModel{});
  // A nominal model that states the bench reference's accuracy keeps it.
  if (model.reference == ReferenceAccuracy{}) model.reference = reference;
  std::string missing;
  auto take = [&](const std::optional<double>& value, bool has_nominal, const char* key, auto&& assign) {
    if (value.has_value()) {
      assign(*value);
    } else if (!has_nominal) {
      missing += (missing.empty() ? "" : ", ") + std::string(key);
    }
  };
  const bool n = nominal.has_value();
  take(d.gyro_arw_rad_rts, n, "gyro_arw", [&](double v) { model.gyro.white_noise_density.setConstant(v); });
  take(d.gyro_bias_sigma_rad_s, n, "gyro_bias_sigma", [&](double v) {
    for (auto& b : model.gyro.bias) b.sigma = v;
  });
  take(d.gyro_bias_tau_s, n, "gyro_bias_tau", [&](double v) {
    for (auto& b : model.gyro.bias) b.tau_s = v;
  });
  take(d.acc_vrw_mps_rts, n, "acc_vrw", [&](double v) { model.acc.white_noise_density.setConstant(v); });
  take(d.acc_bias_sigma_mps2, n, "acc_bias_sigma", [&](double v) {
    for (auto& b : model.acc.bias) b.sigma = v;
  });
  take(d.acc_bias_tau_s, n, "acc_bias_tau", [&](double v) {
    for (auto& b : model.acc.bias) b.tau_s = v;
  });
  if (!missing.empty()) {
    return absl::FailedPreconditionError("no a-priori value for " + missing +
                                         ": the run's datasheet lacks it and no nominal model was given");
  }
  return model;
}

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

absl::Status AddEffects(const BenchRun& run, const std::vector<std::string>& selectors, double update_interval_s,
                        double diffuse_prior_scale, ErrorModel& model) {
  auto selected = ParseEffectSelectors(selectors);
  if (!selected.ok()) return selected.status();
  return AddEffects(run, *selected, update_interval_s, diffuse_prior_scale, model);
}

absl::Status AddEffects(const BenchRun& run, const std::vector<SelectedTerm>& selected,
                        double update_interval_s, double diffuse_prior_scale, ErrorModel& model) {
  for (const auto& [selector, term, onset_s, time_constant_s] : selected) {
    if (model.FindEffect(term) >= 0) continue;
    ModelEffect e;
    e.term = term;
    if (term.family->kind == EffectKind::kTransient && !time_constant_s.has_value()) {
      return absl::InvalidArgumentError("effect '" + selector + "' is a warm-up: name its time constant, " +
                                        term.Name() + "@SECONDS, or add it after a scan has estimated one");
    }
    if (term.family->kind == EffectKind::kFault) {
      if (!onset_s.has_value()) {
        return absl::InvalidArgumentError(
            "effect '" + selector + "' is a fault: name its onset, " + term.Name() +
            "@SECONDS, or add it after a scan has estimated the onset");
      }
      e.onset_s = *onset_s;
    }
    const SensorTriadModel& triad = term.family->sensor == Sensor::kGyro ? model.gyro : model.acc;
    // The sensor's white noise averaged over one update interval: the size of
    // error the data resolve in one step.
    const double noise = triad.white_noise_density.maxCoeff() / std::sqrt(update_interval_s);
    const double drift = std::max({triad.bias[0].sigma, triad.bias[1].sigma, triad.bias[2].sigma});
    const double scale = diffuse_prior_scale * std::max(noise, drift);
    if (term.family->kind == EffectKind::kTransient) {
      // A start value on the scale of a turn-on bias.
      AddWarmUp(term, *time_constant_s, scale, model);
      continue;
    }
    if (term.family->kind == EffectKind::kFault) {
      // A step on the scale of a turn-on bias; a ramp that reaches it over the run.
      e.prior_sigma[0] = term.family->regressor == Regressor::kRamp
                             ? scale / std::max(run.DurationS(), 1.0)
                             : scale;
      model.effects.push_back(e);
      continue;
    }
    switch (term.family->process) {
      case RandomProcess::kNone: {
        const auto rms = pipeline::RegressorRms(run, term);
        for (int p = 0; p < term.family->parameters_per_term; ++p) {
          // An effect the run cannot excite keeps a prior on the scale of the drift itself.
          const double r = rms[static_cast<size_t>(p)];
          e.prior_sigma[static_cast<size_t>(p)] = r > 0.0 ? scale / r : scale;
        }
        break;
      }
      case RandomProcess::kRandomWalk:
        // A walk that reaches the drift's σ over the drift's own correlation time.
        e.random_walk_density =
            drift / std::sqrt(std::max(triad.bias[term.axis].tau_s, update_interval_s));
        break;
      case RandomProcess::kSecondOrderMarkov:
        e.second_order_sigma = triad.bias[term.axis].sigma;
        e.second_order_alpha_per_s = 1.0 / std::max(triad.bias[term.axis].tau_s, update_interval_s);
        e.second_order_beta_rad_s = 2.0 * std::numbers::pi * e.second_order_alpha_per_s;
        break;
      case RandomProcess::kDecayFromStart:  // added above
        break;
    }
    model.effects.push_back(e);
  }
  return absl::OkStatus();
}

namespace {

using pipeline::Progress;

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

// Where model A's a-priori values came from (DecisionKind::kAPrioriModel).
void RecordAPrioriSource(DecisionLog& decisions, std::string source, std::string why = "") {
  Decision d;
  d.kind = DecisionKind::kAPrioriModel;
  d.adopted = true;
  d.qualifiers.push_back(std::move(source));
  if (!why.empty()) d.qualifiers.push_back(std::move(why));
  decisions.Record(std::move(d));
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
    RecordAPrioriSource(decisions, "datasheet");
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
      RecordAPrioriSource(decisions, "nominal");
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
  RecordAPrioriSource(decisions, "allan_fit", model.ok() ? "" : "no_specification");
  return out;
}

// Model A as an earlier analysis identified it, with the baseline effects
// `base` holds that it lacks. What this analysis measures again is left out
// of the earlier estimates: the dominant constants removed from the run
// (STATIC) and the filter's estimates of the model's constant effects
// (FILTER, from model A's pass).
pipeline::Identification IdentifiedEarlier(const IdentifiedModel& earlier, const ErrorModel& base,
                                           DecisionLog& decisions) {
  pipeline::Identification out;
  out.model = earlier.model;
  for (const ModelEffect& e : base.effects) {
    if (out.model.FindEffect(e.term) < 0) out.model.effects.push_back(e);
  }
  for (const ParameterEstimate& p : earlier.identified) {
    if (p.method != EstimationMethod::kStaticMeans && p.method != EstimationMethod::kFilterState) {
      out.identified.push_back(p);
    }
  }
  RecordAPrioriSource(decisions, "earlier_analysis");
  return out;
}

// Model A: the identified model's final pass with the missing-effect scan,
// or the identification's scanned pass when it is of the same model.
absl::StatusOr<pipeline::ScannedModel> ScanModelA(const pipeline::RunContext& c, const AnalysisRequest& request,
                                                  pipeline::Identification& id, DecisionLog& decisions) {
  Progress(c.options, 0.65, "missing-effect scan");
  if (id.scanned.has_value() && id.scanned->pass.model == id.model) {
    decisions.Append(id.scanned->decisions);
    return std::move(*id.scanned);
  }
  auto pass = pipeline::RunPass(c.run, c.epochs, id.model, c.samples, c.options, /*with_scan=*/true);
  if (!pass.ok()) return pass.status();
  // Model A from an earlier analysis: what its structure tests found nothing in stands.
  pipeline::SettledStructures settled;
  if (request.identified_base.has_value() && !c.options.retest_settled_structures) {
    settled.candidates = request.identified_base->structure_outcomes;
    decisions.Note("model A's likelihood tests of walks and second-order drifts ran again only where the earlier "
                    "analysis found a structure or did not test one");
  }
  pipeline::ScannedModel a;
  a.found = pipeline::FindMissingEffects(c, *pass, c.options, &decisions, settled);
  a.pass = *std::move(pass);
  return a;
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

// Model A's analysis, or model B with the warm-ups that explain A's failures
// at the run's start (pipeline::ExplainTheStartByWarmUps).
absl::StatusOr<Analysis> ModelAOrItsStartExplained(const pipeline::RunContext& context,
                                                   pipeline::ScannedModelA model_a) {
  auto settled = pipeline::ExplainTheStartByWarmUps(context, model_a);
  if (!settled.ok()) return settled.status();
  if (settled->has_value()) return **std::move(settled);
  Analysis only_a;
  only_a.report = std::move(model_a.report);
  only_a.model = model_a.pass.model;
  if (context.options.keep_series) pipeline::FillSeries(model_a.pass, only_a.series);
  return only_a;
}

// Model A: identified here or taken from the request's base, its pass
// scanned for missing effects, and its report, with the identified
// parameters and notes later models carry on.
struct ModelA {
  pipeline::ScannedModel scanned;
  AnalysisReport report;
  std::vector<ParameterEstimate> identified;
  DecisionLog decisions;
};

absl::StatusOr<ModelA> RunModelA(const pipeline::PreparedRun& prepared, const pipeline::RunContext& context,
                                 const AnalysisRequest& request) {
  DecisionLog decisions = prepared.screened->decisions;
  pipeline::Identification identification;
  identification.model = prepared.base;
  if (request.identified_base.has_value()) {
    identification = IdentifiedEarlier(*request.identified_base, identification.model, decisions);
  } else if (context.options.identify) {
    auto identified = pipeline::IdentifyModel(context, prepared.screened->allan, identification.model, decisions);
    if (!identified.ok()) return identified.status();
    identification = *std::move(identified);
  }
  auto scanned = ScanModelA(context, request, identification, decisions);
  if (!scanned.ok()) return scanned.status();
  ModelA a{*std::move(scanned), {}, std::move(identification.identified), {}};
  const ident::RemovedConstants& removed = prepared.screened->removed_constants;
  a.identified.insert(a.identified.begin(), removed.estimates.begin(), removed.estimates.end());
  a.report = pipeline::ReportOf(context, a.scanned.pass, a.scanned.found, a.identified, decisions);
  a.decisions = std::move(decisions);
  return a;
}

// What an Add reads of model A: its pass reduced to the model and the scan
// (with the states the scan refers to).
std::shared_ptr<const pipeline::ModelAOutcome> OutcomeOf(ModelA a) {
  auto out = std::make_shared<pipeline::ModelAOutcome>();
  out->model = std::move(a.scanned.pass.model);
  out->layout = std::move(a.scanned.pass.layout);
  out->scan = std::move(a.scanned.pass.scan);
  out->found = std::move(a.scanned.found);
  out->report = std::move(a.report);
  out->identified = std::move(a.identified);
  out->decisions = std::move(a.decisions);
  return out;
}

// Model A's outcome for an Add from the request's identified base as
// `outcomes` keeps it. The caller's key names the base; the model this
// analysis would start from checks that it names the same one.
std::shared_ptr<const pipeline::ModelAOutcome> KeptModelA(const pipeline::PreparedRun& prepared,
                                                          const AnalysisRequest& request,
                                                          pipeline::ModelAOutcomes* outcomes) {
  if (outcomes == nullptr || !request.identified_base.has_value()) return nullptr;
  auto kept = outcomes->Find();
  DecisionLog unused;
  if (kept == nullptr || !(kept->model == IdentifiedEarlier(*request.identified_base, prepared.base, unused).model)) {
    return nullptr;
  }
  outcomes->Reused();
  return kept;
}

}  // namespace

namespace pipeline {

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

std::size_t ModelAOutcome::Bytes() const {
  // The scan's n × p sensitivity, p × p information and per-segment scores;
  // the report's candidates.
  const std::size_t p = scan != nullptr ? scan->columns().size() : 0;
  const std::size_t n = layout != nullptr ? static_cast<std::size_t>(layout->size()) : 0;
  std::size_t segment_scores = 0;
  if (scan != nullptr) {
    for (const Eigen::MatrixXd& m : scan->score_by_segment()) segment_scores += static_cast<std::size_t>(m.size());
  }
  return sizeof(ModelAOutcome) + (n * p + p * p + p + segment_scores) * sizeof(double) +
         (report.effect_candidates.size() + found.candidates.size()) * sizeof(EffectCandidate) * 2;
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

absl::StatusOr<std::shared_ptr<const ModelAOutcome>> ModelAOutcomeOf(const PreparedRun& prepared,
                                                                     const AnalysisRequest& request,
                                                                     const AnalysisOptions& requested_options,
                                                                     ModelAOutcomes* outcomes) {
  if (auto kept = KeptModelA(prepared, request, outcomes); kept != nullptr) return kept;
  const AnalysisOptions options = prepared.OptionsFor(requested_options);
  auto a = RunModelA(prepared, prepared.Context(options), request);
  if (!a.ok()) return a.status();
  std::shared_ptr<const ModelAOutcome> outcome = OutcomeOf(*std::move(a));
  if (outcomes != nullptr && request.identified_base.has_value()) outcomes->Keep(outcome);
  return outcome;
}

absl::StatusOr<Analysis> AnalyzePrepared(const PreparedRun& prepared, const AnalysisRequest& request,
                                         const AnalysisOptions& requested_options, ModelAOutcomes* outcomes) {
  const AnalysisOptions options = prepared.OptionsFor(requested_options);
  const RunContext context = prepared.Context(options);
  absl::StatusOr<Analysis> out;
  if (!request.discover && !request.add_effects.empty()) {
    // An Add reads model A's model, scan and report only: its pass is let go
    // before model B's runs.
    auto a = ModelAOutcomeOf(prepared, request, options, outcomes);
    if (!a.ok()) return a.status();
    const ModelAOutcome& kept = **a;
    out = AddAndCompare(context, request.add_effects,
                        ModelAForAdd{kept.model, kept.scan.get(), kept.found, kept.report, kept.identified,
                                     kept.decisions});
  } else {
    auto a = RunModelA(prepared, context, request);
    if (!a.ok()) return a.status();
    ScannedModelA model_a{a->scanned.pass, a->scanned.found, std::move(a->report), std::move(a->identified),
                          std::move(a->decisions)};
    out = request.discover ? Discover(context, std::move(model_a))
                           : ModelAOrItsStartExplained(context, std::move(model_a));
  }
  if (!out.ok()) return out.status();
  const ScreenedRun& screened = *prepared.screened;
  out->report.allan = screened.allan;
  const RecordedSamples recorded{screened.run, screened.removed_constants.gyro_rad_s,
                                 screened.removed_constants.acc_mps2, screened.screening.spikes};
  out->report.plain_words = PlainWordsVerdict(out->report, recorded, options.monitor.family_wise_alpha);
  Progress(options, 1.0, "done");
  return out;
}

}  // namespace pipeline

absl::StatusOr<Analysis> Analyze(const BenchRun& run, const AnalysisRequest& request,
                                 const AnalysisOptions& options) {
  return Analyze(BenchRun(run), request, options);
}

absl::StatusOr<Analysis> Analyze(BenchRun&& run, const AnalysisRequest& request, const AnalysisOptions& options) {
  auto prepared = pipeline::PrepareRun(std::move(run), request, options);
  if (!prepared.ok()) return prepared.status();
  return pipeline::AnalyzePrepared(**prepared, request, options, nullptr);
}

}  // namespace insdiag::engine
