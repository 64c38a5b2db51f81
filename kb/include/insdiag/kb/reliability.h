// Life statistics of the fleet's modules (docs/FLEET.md).
//
// 2-parameter Weibull with right censoring, by maximum likelihood
// (Lawless, Statistical Models and Methods for Lifetime Data, 2nd ed., 2003,
// §5.2.2; Meeker & Escobar, Statistical Methods for Reliability Data, 1998, §8.2):
//   ℓ(β, η) = r ln β − rβ ln η + (β − 1) Σ_F ln t_i − Σ_all (t_j/η)^β
// Given β, the scale maximising ℓ is η̂(β) = (Σ_all t_j^β / r)^{1/β}; the
// profile score in β,
//   g(β) = 1/β + (1/r) Σ_F ln t_i − Σ_all t_j^β ln t_j / Σ_all t_j^β,
// decreases monotonically, so β̂ is its one root (bracketed bisection, then
// Newton polish). Standard errors from the observed information
// −∂²ℓ/∂(β, η)² at the estimate; bounds are Wald intervals on the log scale,
//   β̂ exp(± z se(β̂)/β̂),
// and B10 life (10 % failed) = η (−ln 0.9)^{1/β} with the delta method on ln B10.
//
// MTBF of a module type under a constant failure rate, from T hours of
// exposure and r failures, time-terminated test (MIL-HDBK-781A, 5.9.1;
// Epstein & Sobel, JASA 48, 1953):
//   MTBF = T/r,  lower = 2T/χ²(1 − α/2; 2r + 2),  upper = 2T/χ²(α/2; 2r) (none for r = 0)
#pragma once

#include <absl/status/statusor.h>

#include <cstdint>
#include <span>

namespace insdiag::kb {

struct LifeObservation {
  double hours = 0.0;   // life so far (failed: at failure; censored: at removal or now)
  bool failed = false;
};

struct WeibullEstimate {
  std::int64_t failures = 0;
  std::int64_t suspensions = 0;
  double shape = 0.0;        // β
  double scale_hours = 0.0;  // η
  double shape_std_error = 0.0;
  double scale_std_error_hours = 0.0;
  double shape_lower = 0.0, shape_upper = 0.0;
  double scale_lower_hours = 0.0, scale_upper_hours = 0.0;
  double b10_hours = 0.0, b10_lower_hours = 0.0, b10_upper_hours = 0.0;
  double log_likelihood = 0.0;
};

// FAILED_PRECONDITION with fewer than 2 failures or fewer than 2 distinct
// failure times (the likelihood has no interior maximum); INVALID_ARGUMENT
// for a non-positive life or a confidence outside (0, 1).
absl::StatusOr<WeibullEstimate> FitWeibull(std::span<const LifeObservation> lives, double confidence);

struct MtbfEstimate {
  double mtbf_hours = 0.0;   // 0 without failures
  double lower_hours = 0.0;
  double upper_hours = 0.0;  // 0: unbounded (no failures)
};

MtbfEstimate EstimateMtbf(double exposure_hours, std::int64_t failures, double confidence);

}  // namespace insdiag::kb
