// The stages that change the model after model A's scan: the loop's
// `--discover` (add the most significant missing effect, re-run, repeat) and
// `--add` (model B = A + the effects named, compared with A), and what both
// need — a model extended with priors from A's scan, and the comparison.
#pragma once

#include <absl/status/statusor.h>

#include <string>
#include <vector>

#include "analysis/missing_effects.h"
#include "analysis/model_pass.h"
#include "analysis/run_context.h"

namespace insdiag::engine::pipeline {

// What an Add reads of model A: its model; its missing-effect scan's score
// and information (the added effects' priors and the likelihood ratio
// predicted for them); what the scan found; its report, with the identified
// parameters and notes later models carry on.
struct ModelAForAdd {
  const ErrorModel& model;
  const ScoreTestObserver* scan;
  const Findings& found;
  AnalysisReport report;
  std::vector<ParameterEstimate> identified;
  DecisionLog decisions;
};

// Model A: the identified model's whole pass, what its scan found and its
// report, with the identified parameters and notes later models carry on.
struct ScannedModelA {
  const ModelPass& pass;
  const Findings& found;
  AnalysisReport report;
  std::vector<ParameterEstimate> identified;
  DecisionLog decisions;

  ModelAForAdd ForAdd() const { return {pass.model, pass.scan.get(), found, report, identified, decisions}; }
};

// Walks the loop from model A; the analysis's report is the last model's,
// with the path and the comparison against A.
absl::StatusOr<Analysis> Discover(const RunContext& c, ScannedModelA a);

// Model B = A + `effects`, its report compared with A's.
absl::StatusOr<Analysis> AddAndCompare(const RunContext& c, const std::vector<std::string>& effects, ModelAForAdd a);

// A unit that settles after power-up fails at its start: the filter, started
// from the run's mean biases, meets the start's. When model A's only failures
// begin within the span at the start that no onset can be placed in
// (onset_scan.min_side_s), it has no finding, and warm-ups are listed that
// lower the BIC (Schwarz, Ann. Stat. 6(2), 1978), model B carries them at
// their listed time constants. B is the analysis when its verdict is better
// and it has neither a failure in that span nor a finding; otherwise nullopt
// (model A stands, with its warm-ups listed for the user to add).
absl::StatusOr<std::optional<Analysis>> ExplainTheStartByWarmUps(const RunContext& c, const ScannedModelA& a);

// The identified parameters of a model that took structures of `found`:
// what the likelihood identified with each (a walk's K or a pair's σ₂, τ₂
// and period, and the drift σ fitted with it) replaces the earlier estimate
// of the same name.
std::vector<ParameterEstimate> WithTakenStructures(std::vector<ParameterEstimate> identified,
                                                   const ErrorModel& model, const Findings& found);

// Model `base` plus `selectors`, with priors from what `base`'s scan and
// correlation processing found; anything not found gets the diffuse prior.
absl::StatusOr<ErrorModel> ExtendModel(const BenchRun& run, const ErrorModel& base,
                                       const std::vector<std::string>& selectors, const ScoreTestObserver* scan,
                                       const Findings& found, const AnalysisOptions& options);

ModelComparison Compare(const ErrorModel& a, const ErrorModel& b, const AnalysisReport& ra, const AnalysisReport& rb,
                        double predicted_lr);

// Whether `term_name` is one of the terms `selector` (a term or a family) stands for.
bool SelectorCovers(const std::string& selector, const std::string& term_name);

// Model A's score statistic for adding `added` jointly (the likelihood ratio it predicts).
double PredictedLikelihoodRatio(const ScoreTestObserver* scan, const std::vector<std::string>& added,
                                const Findings& found);

}  // namespace insdiag::engine::pipeline
