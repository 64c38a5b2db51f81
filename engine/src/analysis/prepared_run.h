// An analysis in two halves (engine/src/analysis.cc): the run's preparation,
// which depends on the run, the a-priori inputs and the options only, and
// what follows it from model A on. The preparation is what analyses of one
// run share (insdiag/engine/analysis_cache.h): the samples screened, the
// a-priori model chosen, the run condensed to its epochs.
#pragma once

#include <absl/status/statusor.h>

#include <array>
#include <memory>
#include <optional>
#include <vector>

#include "analysis/missing_effects.h"
#include "analysis/model_change.h"
#include "analysis/run_context.h"
#include "insdiag/engine/analysis.h"
#include "insdiag/engine/decision.h"
#include "insdiag/engine/finder/score_test.h"
#include "insdiag/engine/ident/allan.h"
#include "insdiag/engine/ident/static_constants.h"

namespace insdiag::engine::pipeline {

// What the preparation makes of the run before the baseline effects: the
// run screened, the a-priori model chosen, the Allan analysis. It depends on
// the run, the nominal model and the options only.
struct ScreenedRun {
  ScreenedRun() = default;
  ScreenedRun(const ScreenedRun&) = delete;
  ScreenedRun& operator=(const ScreenedRun&) = delete;

  BenchRun run;  // screened, spikes repaired, dominant constants removed
  // What the requested options became for this run (its update interval);
  // `progress` left empty: each analysis brings its own.
  AnalysisOptions options;
  std::vector<std::array<double, 6>> reference_measurements;
  SampleScreening screening;
  std::optional<ident::AllanResult> allan;
  APriori a_priori;
  ident::RemovedConstants removed_constants;
  RawSampleEvidence raw_samples;
  ident::DriftCeilings drift_ceilings;
  // The preparation's notes, which every report of the run starts from.
  DecisionLog decisions;

  // About what it holds in memory: the samples and the reference's measurements.
  std::size_t Bytes() const;
};

// The run as every stage after condensing reads it: screened, and condensed
// with the a-priori model and the baseline effects as its pilot. Not
// movable: a RunContext refers into it.
struct PreparedRun {
  PreparedRun() = default;
  PreparedRun(const PreparedRun&) = delete;
  PreparedRun& operator=(const PreparedRun&) = delete;

  std::shared_ptr<const ScreenedRun> screened;
  ErrorModel base;  // the a-priori model with the baseline effects
  EpochRun epochs;

  // The context the later stages share, under `options` (OptionsFor's).
  RunContext Context(const AnalysisOptions& options) const {
    const ScreenedRun& s = *screened;
    return RunContext{s.run,     epochs,        s.reference_measurements, s.screening, options,
                      s.a_priori, s.raw_samples, s.drift_ceilings};
  }
  // An analysis's own options at this run's update interval.
  AnalysisOptions OptionsFor(const AnalysisOptions& requested) const {
    AnalysisOptions out = requested;
    out.filter.update_interval_s = screened->options.filter.update_interval_s;
    return out;
  }
  // About what the epochs hold in memory (the screened run's apart).
  std::size_t EpochBytes() const;
};

// Records where model A's a-priori values came from (DecisionKind::kAPrioriModel).
void RecordAPrioriSource(DecisionLog& decisions, std::string source, std::string why = "");

// Screens `run`, chooses the a-priori model from `request.nominal`, adds
// `request.baseline_effects` and condenses the run.
absl::StatusOr<std::unique_ptr<PreparedRun>> PrepareRun(BenchRun&& run, const AnalysisRequest& request,
                                                        const AnalysisOptions& options);
// The same from a run already screened for the same nominal model and
// options: only the condensation, with `request.baseline_effects` in its pilot.
absl::StatusOr<std::unique_ptr<PreparedRun>> PrepareRun(std::shared_ptr<const ScreenedRun> screened,
                                                        const AnalysisRequest& request);

// What an Add reads of model A besides its report: the model, its
// missing-effect scan's score and information (the added effects' priors and
// the likelihood ratio predicted for them), and what the scan found.
struct ModelAOutcome {
  ErrorModel model;
  std::unique_ptr<StateLayout> layout;  // the scan's states
  std::unique_ptr<ScoreTestObserver> scan;
  Findings found;
  AnalysisReport report;
  std::vector<ParameterEstimate> identified;
  DecisionLog decisions;
  std::size_t Bytes() const;

  ModelAForAdd ForAdd() const { return {model, scan.get(), found, report, identified, decisions}; }
};

// Where an analysis from an earlier one's model A (AnalysisRequest::
// identified_base) finds model A's outcome, and leaves it for the next.
class ModelAOutcomes {
 public:
  virtual ~ModelAOutcomes() = default;
  // Model A's outcome for this request's identified base, null if none is kept.
  virtual std::shared_ptr<const ModelAOutcome> Find() const = 0;
  // The outcome Find gave was taken.
  virtual void Reused() = 0;
  // Keeps `outcome` in place of any other for the same base.
  virtual void Keep(std::shared_ptr<const ModelAOutcome> outcome) = 0;
};

// Model A's outcome for an Add: `outcomes`' where it keeps one for the
// request's identified base, else computed (and kept there, where given).
absl::StatusOr<std::shared_ptr<const ModelAOutcome>> ModelAOutcomeOf(const PreparedRun& prepared,
                                                                     const AnalysisRequest& request,
                                                                     const AnalysisOptions& options,
                                                                     ModelAOutcomes* outcomes);

// The analysis of a prepared run: identification (or model A taken from
// `request.identified_base`), model A's scan, then the loop's step asked for.
// `outcomes`, where given, serves and keeps model A of an Add from an
// identified base.
absl::StatusOr<Analysis> AnalyzePrepared(const PreparedRun& prepared, const AnalysisRequest& request,
                                         const AnalysisOptions& options, ModelAOutcomes* outcomes);

}  // namespace insdiag::engine::pipeline
