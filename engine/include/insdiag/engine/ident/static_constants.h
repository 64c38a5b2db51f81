// The run's constant sensor biases measured directly from the samples, before
// any filter pass, and the dominant ones removed.
//
// Over a static segment (allan.h) the table holds the body at a known
// attitude C_b^n, and a perfect unit reads (Titterton & Weston, Strapdown
// Inertial Navigation Technology, 2nd ed., §10.3: the multi-position static
// test):
//   ω_ib^b = (C_b^n)ᵀ ω_ie^n          Earth rate at the site (wgs84.h)
//   f_ib^b = (C_b^n)ᵀ (0, 0, −g)ᵀ     normal gravity at the site, NED
// The mean of the reading minus this over every static sample is each axis'
// constant bias b̂ (its turn-on bias plus the drift's mean over those
// samples). Its standard error from the a-priori model, for a total static
// time T: white noise N²/T and the mean of a first-order Gauss–Markov drift,
//   Var = N²/T + (2σ²τ/T)·(1 − (τ/T)(1 − e^{−T/τ}))
// (Papoulis & Pillai, Probability, Random Variables and Stochastic
// Processes, 4th ed., §9-5: the variance of a time average), or the batch
// means' standard error where the data scatter more (an a-priori drift
// smaller than the unit's).
//
// Why measure them before the filter. The a-priori model holds a constant
// bias only as its drift state, N(0, σ²). A unit far from that model — a
// MEMS unit's turn-on bias of 0.1–1 °/s under a drift of 10 °/h, hundreds of
// drift σ — is explained by nothing the filter may try: maximum likelihood
// inflates the drift σ and the noise to absorb it, and the scan's one-step
// estimates leave their linear range (a 100 % scale factor on a static run).
// Such a bias is dominant: beyond `drift_sigmas` a-priori drift σ and beyond
// `standard_errors` of its own standard error — and every batch of the
// static time holds at least `batch_share` of it, on the same side. A
// constant is there from turn-on; a bias step inside the run moves the mean
// of the static samples as far (tens of drift σ where the label's drift is
// far below the unit's) while the batches before the
// step sit near zero, and removing that mean leaves two levels that neither
// the drift nor the step explains. The analysis removes the
// dominant biases from the samples and reports them as identified turn-on
// biases; everything after (identification, scan, comparison) works on the
// remainder, where the a-priori model is again a starting point.
#pragma once

#include <absl/status/statusor.h>

#include <array>
#include <string>
#include <vector>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/ident/allan.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/model/error_model.h"
#include "insdiag/engine/parameter_estimate.h"

namespace insdiag::engine::ident {

struct DominantConstantOptions {
  // A hidden turn-on bias of three tolerances of a navigation-grade type
  // sits at about 15 a-priori drift σ, and the missing-effect scan finds it
  // (the loop's own tests). MEMS-class turn-on biases sit at 20–150 σ of
  // their drift, where a Gaussian drift prior gives them a probability below
  // e^{−200}.
  double drift_sigmas = 20.0;
  double standard_errors = 5.0;
  // Batches for the data's own standard error of the means: the larger of it
  // and the a-priori model's is reported.
  int batches = 20;
  // The share of the constant every batch mean must hold. A step at a share
  // f of the static time moves the mean to (1 − f) of its size and leaves the
  // batches before it at zero; a constant of 20 drift σ scatters by about 1.5
  // σ a batch.
  double batch_share = 0.5;
};

// One sensor axis' measured constant bias.
struct StaticConstant {
  EffectTerm term;            // the catalogue's turn-on bias of the axis, as it is reported
  double bias = 0.0;          // in term.family->unit (rad/s | m/s²)
  double std_error = 0.0;
  double drift_sigma = 0.0;   // the a-priori drift σ it is weighed against
  // The batch mean nearest zero, signed positive on the bias's side (the
  // bias itself when the static time is too short to batch).
  double weakest_batch_bias = 0.0;
  bool dominant = false;
};

struct StaticConstants {
  double static_s = 0.0;  // total static time measured
  // Gyro x, y, z, accelerometer x, y, z (SensorAxisIndex order).
  std::array<StaticConstant, 6> axes;

  bool AnyDominant() const;
};

// What the a-priori model says of a constant bias. A datasheet's or a unit
// type's drift σ bounds it: a constant far beyond it is dominant. A model
// fitted to the run's Allan deviation says nothing of it — the Allan
// variance of a constant is zero (IEEE Std 952, Annex C: the curve is blind
// to a fixed offset) — so every constant the static samples resolve, beyond
// `standard_errors` of its standard error and held by every batch, is
// dominant: the unit far from any prior gets its constant terms first, on
// every axis.
enum class ConstantPrior { kBoundedByDrift, kNone };

// The constant bias of every sensor axis over the static segments, weighed
// against the a-priori model. FailedPrecondition when the run has no static
// segment.
absl::StatusOr<StaticConstants> MeasureStaticConstants(const BenchRun& run,
                                                       const std::vector<StaticSegment>& segments,
                                                       const ErrorModel& a_priori,
                                                       const DominantConstantOptions& options = {},
                                                       ConstantPrior prior = ConstantPrior::kBoundedByDrift);

// The dominant constants taken out of a run's samples: as identified
// parameters (method "STATIC", a-priori 0), and as what was subtracted from
// every sample.
struct RemovedConstants {
  std::vector<ParameterEstimate> estimates;
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d acc_mps2 = Eigen::Vector3d::Zero();
};

// Measures the constants on `segments`, subtracts the dominant ones from
// every sample of `run` and says so in `notes`. None when none is dominant or
// the run has no static segment.
RemovedConstants RemoveDominantConstants(BenchRun& run, const std::vector<StaticSegment>& segments,
                                                       const ErrorModel& a_priori,
                                                       const DominantConstantOptions& options, ConstantPrior prior,
                                                       std::vector<std::string>& notes);

}  // namespace insdiag::engine::ident
