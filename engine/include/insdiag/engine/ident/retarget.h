// Retargeting of the error model's parameters (the seed's "retargeting of
// parameters of the error model"): the filter runs with the a-priori model,
// the identification tells the unit's actual parameters, and the model is
// re-tuned with them until they settle.
//
//   drifts     σ, τ of each base Gauss–Markov drift from correlation processing
//              of its smoothed estimate (correlation.h), where the run resolves it
//   noise      angle / velocity random walk and quantisation from the Allan fit
//              of the static segments (allan.h), where resolved
//   reference  the observation noise r of a channel group is raised when its
//              innovations are larger than predicted — covariance matching,
//              r̂ = mean(ν²) − mean(h P hᵀ) (Mehra, "Approaches to adaptive
//              filtering", IEEE Trans. AC 17(5), 1972): the unit moved in ways the
//              bench's reference did not record
#pragma once

#include <string>
#include <vector>

#include "insdiag/engine/filter/forward_filter.h"
#include "insdiag/engine/filter/smoother.h"
#include "insdiag/engine/ident/allan.h"
#include "insdiag/engine/ident/correlation.h"
#include "insdiag/engine/model/error_model.h"
#include "insdiag/engine/parameter_estimate.h"
#include "insdiag/engine/report.h"

namespace insdiag::engine::ident {

// Smoother options that also compute the error autocovariance the
// correlation processing of the base drifts needs.
SmootherOptions DriftSmootherOptions(const ErrorModel& model, const StateLayout& layout, const ForwardPass& forward,
                                     const CorrelationOptions& options);

// Correlation processing of every base drift state of a smoothed pass.
std::vector<DriftCorrelation> CorrelateDrifts(const ForwardPass& forward, const SmoothedPass& smoothed,
                                              const StateLayout& layout, const CorrelationOptions& options,
                                              std::vector<std::string>* notes);

struct RetargetResult {
  ErrorModel model;
  std::vector<ParameterEstimate> identified;  // ACF estimates of the resolved drifts
  bool settled = true;  // no parameter moved by more than the tolerance
};

// σ and τ of every resolved drift from its exponential fit, reported; the
// model takes them only where the data reject the a-priori pair — the Wald
// statistic of (ln σ₀, ln τ₀) against the fit's covariance beyond χ²₂(1 − α)
// — so that a model the data do not contradict stays as it was. Settled when
// every change is below `settle_log_ratio` in log or below one standard error.
RetargetResult RetargetDrifts(const ErrorModel& current, const ErrorModel& a_priori,
                              const std::vector<DriftCorrelation>& drifts, double settle_log_ratio, double alpha);

// White-noise densities and quantisation from the Allan fit where resolved
// and where the fit rejects the a-priori value (Wald statistic beyond
// χ²₁(1 − α), as for the drifts); returns the estimates it used (method ALLAN).
std::vector<ParameterEstimate> ApplyAllanNoise(const AllanResult& allan, const ErrorModel& a_priori,
                                               ErrorModel& model, double alpha);

// Raises the reference's position / velocity noise when a channel group's
// innovations exceed their predicted variance beyond the χ² band at
// `alpha` and are not positively correlated (a missing effect, not a
// missing noise); true when it changed the model (a note says by how much).
bool MatchReferenceNoise(const ForwardPass& forward, double alpha, ErrorModel& model,
                         std::vector<std::string>* notes);

}  // namespace insdiag::engine::ident
