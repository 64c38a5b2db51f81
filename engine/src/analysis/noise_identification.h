// The identification's noise terms (docs/IDENTIFICATION.md): the Allan
// fit's white noise and quantisation in the model, a quantisation kept only
// where the innovations' likelihood prefers it, the terms the Allan fit left
// at bounds re-tuned by maximum likelihood, and the bench's reference noise
// fitted where the innovations reject its stated accuracy. The drifts'
// identification around them is identification.h's.
#pragma once

#include <absl/status/status.h>

#include <optional>
#include <string>
#include <vector>

#include "analysis/run_context.h"
#include "insdiag/engine/decision.h"
#include "insdiag/engine/filter/forward_filter.h"
#include "insdiag/engine/ident/allan.h"

namespace insdiag::engine::pipeline {

// The Allan fit's noise terms in the model, and its estimates other than the
// drifts' (those are identified on the whole run; the Allan Markov term of
// the static segments only seeds an a-priori model).
std::vector<ParameterEstimate> ApplyAllanNoise(const RunContext& c, const ident::AllanResult& allan,
                                               ErrorModel& base);

// The accelerometers' quantisation the Allan fit found where the a-priori
// model states none, kept only where the innovations' likelihood prefers it.
// Over the few cluster times at a low rate's short end (at 1 Hz, τ of 1, 2
// and 4 s) a quantisation term's 3Q²/τ² trades against the white noise and
// the drift's rise, and the Wald test cannot see that; in the filter it is
// white noise on every velocity observation (forward_filter.cc), which made a
// healthy 1 Hz unit's NIS 0.86 (2Δℓ 340 against the model without it).
// Decided against the a-priori model before the drifts are identified, so
// that it does not bend them, and again against the identified model, since
// against drifts far from the unit's it also absorbs their misfit.
enum class QuantisationTest { kBeforeTheDrifts, kAfterTheDrifts };
void KeepQuantisationTheInnovationsSupport(const RunContext& c, QuantisationTest when,
                                           ErrorModel& model,
                                           std::vector<ParameterEstimate>& identified,
                                           DecisionLog& decisions);

// The bench's reference noise, where the innovations reject its stated
// accuracy. Covariance matching (ident::ScreenReferenceNoise) flags the
// channel groups whose innovations exceed their predicted variance and gives
// an upper end; each flagged group's σ is then the innovations' maximum-
// likelihood value between the model's and twice that end (golden section on
// ln σ, the groups in turn; prediction-error likelihood, Schweppe, IEEE
// Trans. IT-11(1), 1965). The model takes them where 2Δℓ exceeds χ²(groups)
// at α, as the drifts' estimates (Wilks 1938). Matching alone misreads an
// excess of another kind — a healthy MEMS unit turned at 1 Hz had its
// position noise raised to 0.86 mm at 2Δℓ = −1355 — and overstates a real one
// (a bench swaying 1 mm, matched at 1.5–1.9 mm:
// tests/engine/noise_identification_test.cc). `passed` is the model
// `forward` ran; `model` takes the fitted reference. True when it did.
bool FitReferenceNoiseTheInnovationsReject(const RunContext& c, const ForwardPass& forward,
                                           const ErrorModel& passed, ErrorModel& model,
                                           DecisionLog& decisions);

// Terms the Allan fit left at bounds: nothing else re-tunes them (the ACF
// retargeting needs a resolved drift, the Allan fit a resolved density), and
// a bound over-predicts the innovations. Their common scale per group by
// maximum likelihood (retarget.h).
void RetuneUnresolvedNoise(const RunContext& c, const std::optional<ident::AllanResult>& allan,
                           ErrorModel& base, std::vector<ParameterEstimate>& identified,
                           DecisionLog& decisions);

// The reference noise of a model whose drifts were identified from a class
// prior, against one pass of that model (FitReferenceNoiseTheInnovationsReject).
absl::Status FitReferenceNoiseToTheIdentifiedModel(const RunContext& c, ErrorModel& model,
                                                   DecisionLog& decisions);

}  // namespace insdiag::engine::pipeline
