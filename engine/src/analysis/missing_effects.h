// The missing-effect stage: what a scanned model pass lacks — constant terms
// and families by the score test, bias steps and ramps by the onset scan,
// random structures by the innovations' likelihood and by correlation
// processing — ranked together, and the report of the pass.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "analysis/model_pass.h"
#include "analysis/run_context.h"
#include "insdiag/engine/decision.h"
#include "insdiag/engine/ident/correlation.h"
#include "insdiag/engine/ident/drift_likelihood.h"

namespace insdiag::engine::pipeline {

// A random-structure effect proposed by correlation processing or by the
// likelihood's structure tests.
struct StructureProposal {
  ModelEffect effect;
  EffectCandidate candidate;
  // Starting points its screen searched (the fit's profile grid): the
  // Bonferroni factor of its p-value.
  int searched_starts = 1;
  // A walk or pair from the likelihood's tests: its statistic is a
  // likelihood ratio already, and a model that takes it takes its
  // parameters and the drift σ fitted with it, and reports them.
  std::optional<ident::StructureEstimate> fitted;
};

// Everything a report says about model A's pass: fit, identification, candidates.
struct Findings {
  std::vector<EffectCandidate> candidates;
  std::vector<EffectCandidate> families;
  std::vector<StructureProposal> structures;
  std::vector<DriftCorrelation> drifts;
};

// The outcomes of likelihood structure tests that a model need not run again:
// a walk or pair that tests on `candidates`' model found nothing in (below
// the screen's level, or shrunk by the screen's first step). They hold for a
// model that only adds constant or fault effects to that one: an added
// deterministic effect takes residual from a structure and gives it none.
// `measured_on` says, in the report's note, which model they were measured
// on (empty: this one, by an earlier analysis).
struct SettledStructures {
  std::vector<EffectCandidate> candidates;
  std::string measured_on;
};

// Whether a model that adds `selectors` to one keeps that model's settled
// structure outcomes: it adds no random structure.
bool AddsOnlyDeterministicEffects(const std::vector<std::string>& selectors);

// A model's pass scanned for missing effects, what the scan found and the
// notes it wrote.
struct ScannedModel {
  ModelPass pass;
  Findings found;
  DecisionLog decisions;
};

// The missing effects of a scanned pass of the run `c`, under `options`
// (the context's, or a stage's variant of them); `drifts`: correlation
// processing of this pass's smoothed drifts. The likelihood does not test
// again the structures `settled` holds; the report takes their outcomes.
Findings FindMissingEffects(const RunContext& c, const ModelPass& pass, std::vector<DriftCorrelation> drifts,
                            const AnalysisOptions& options, DecisionLog* decisions,
                            const SettledStructures& settled = {});
// Correlation processing of the pass's smoothed drifts (seed eq. 8–9), its
// prose into `decisions` where given.
std::vector<DriftCorrelation> CorrelateDrifts(const ModelPass& pass, const AnalysisOptions& options,
                                              DecisionLog* decisions);
// The same, correlating the pass's drifts first.
Findings FindMissingEffects(const RunContext& c, const ModelPass& pass, const AnalysisOptions& options,
                            DecisionLog* decisions, const SettledStructures& settled = {});

// The significant, identifiable candidate whose predicted ΔBIC is lowest,
// among single terms and whole families; nullptr when none is significant.
const EffectCandidate* LowestBicSignificant(const std::vector<EffectCandidate>& terms,
                                            const std::vector<EffectCandidate>& families,
                                            const AnalysisOptions& options);

// The effect `--discover` adds next.
const EffectCandidate* NextDiscovery(const Findings& found, const AnalysisOptions& options);

// The drifts correlation processing resolved.
DriftSelection ResolvedDrifts(const std::vector<DriftCorrelation>& drifts);

// The report of one scanned pass.
AnalysisReport ReportOf(const RunContext& c, const ModelPass& pass, const Findings& found,
                        const std::vector<ParameterEstimate>& identified, const DecisionLog& decisions);

}  // namespace insdiag::engine::pipeline
