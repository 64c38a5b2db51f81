// The identification stage: the a-priori model's noise from the Allan fit and
// the terms it left at bounds re-tuned (noise_identification.h), then the
// retargeting loop — a pass, correlation processing of the smoothed drifts, a
// re-tuned model — until the parameters settle, and the drifts' final values by the
// innovations' likelihood. On its first pass the a-priori model is scanned:
// when it lacks significant effects, its misfit and those effects compete
// (BIC), and either the drifts are re-tuned or the model is left for the
// effects (docs/IDENTIFICATION.md).
#pragma once

#include <absl/status/statusor.h>

#include <optional>
#include <string>
#include <vector>

#include "analysis/missing_effects.h"
#include "analysis/run_context.h"
#include "insdiag/engine/decision.h"
#include "insdiag/engine/ident/allan.h"

namespace insdiag::engine::pipeline {

struct Identification {
  ErrorModel model;  // the identified model
  std::vector<ParameterEstimate> identified;
  // A pass already scanned for missing effects: the a-priori model's, kept
  // when the identification leaves its model, or when its missing effects go
  // before any re-tune.
  std::optional<ScannedModel> scanned;
};

// Identifies `base` (the a-priori model with the baseline effects) on the run.
absl::StatusOr<Identification> IdentifyModel(const RunContext& c, const std::optional<ident::AllanResult>& allan,
                                             ErrorModel base, DecisionLog& decisions);

}  // namespace insdiag::engine::pipeline
