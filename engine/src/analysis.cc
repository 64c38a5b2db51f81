// The analysis as a pipeline of stages (analysis.h): each stage's inputs and
// outputs are explicit; the stages live in engine/src/analysis/, the run's
// preparation in analysis/run_preparation.cc.
#include "insdiag/engine/analysis.h"

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
#include "insdiag/engine/plain_words.h"

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
  pipeline::RecordAPrioriSource(decisions, "earlier_analysis");
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
    out = AddAndCompare(context, request.add_effects, (*a)->ForAdd());
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
