// The warm-up stage: a bias that settles after power-up (catalogue family
// warm_up), found on the a-priori model before the drifts are identified —
// otherwise the drifts widen to carry the start's departure, and the
// monitor flags the start of a healthy unit's run.
#pragma once

#include <string>
#include <vector>

#include "analysis/run_context.h"
#include "insdiag/engine/model/error_model.h"
#include "insdiag/engine/parameter_estimate.h"

namespace insdiag::engine::pipeline {

// Adds to `model` each sensor axis' warm-up that the score test over time
// constants finds (finder/warm_up_scan.h) at the family-wise level over the
// six axes (Holm), the strongest first, with its time constant and a prior
// σ around its start value, and scans again until no more stand. The
// estimates go into `identified`, what was found into `notes`. Returns how
// many it added.
int AddTheWarmUpsTheRunShows(const RunContext& c, ErrorModel& model, std::vector<ParameterEstimate>& identified,
                             std::vector<std::string>& notes);


}  // namespace insdiag::engine::pipeline
