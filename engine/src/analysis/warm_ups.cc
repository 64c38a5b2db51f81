#include "analysis/warm_ups.h"

#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "analysis/model_pass.h"
#include "insdiag/engine/finder/warm_up_scan.h"
#include "insdiag/engine/model/parameter_field.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine::pipeline {
namespace {

// The turn-on bias of a warm-up's axis.
EffectTerm TurnOnBiasTerm(const EffectTerm& warm_up) {
  const std::string_view family = warm_up.family->sensor == Sensor::kGyro ? "gyro_turn_on_bias" : "acc_turn_on_bias";
  return {FindEffectFamily(family), warm_up.axis, warm_up.axis};
}

std::string TimeConstantName(const EffectTerm& term) {
  return ParameterName(term.Name(), ParameterField::kTau);
}

// The fits whose Holm-adjusted p-value over `fits` is below `alpha`.
std::vector<const WarmUpFit*> Significant(const std::vector<WarmUpFit>& fits, double alpha) {
  std::vector<double> p, adjusted(fits.size());
  for (const WarmUpFit& f : fits) p.push_back(f.identifiable ? f.p_value : 1.0);
  stats::HolmAdjust(p, adjusted);
  std::vector<const WarmUpFit*> out;
  for (size_t i = 0; i < fits.size(); ++i) {
    if (fits[i].identifiable && adjusted[i] < alpha) out.push_back(&fits[i]);
  }
  return out;
}

void AddWarmUp(const WarmUpFit& f, const AnalysisOptions& options, ErrorModel& model,
               std::vector<ParameterEstimate>& identified, std::vector<std::string>& notes) {
  ModelEffect e;
  e.term = f.term;
  e.time_constant_s = f.time_constant_s;
  e.prior_sigma[0] = PriorSigmaAroundEstimate(f.estimate, f.std_error, options);
  model.effects.push_back(e);
  // The bias settles to a value the run did not show before the warm-up was
  // seen: a constant removed as the run's mean, or a drift started at zero,
  // holds the warm-up's mean over the run, of the order of its start value.
  const EffectTerm steady = TurnOnBiasTerm(f.term);
  if (model.FindEffect(steady) < 0) {
    ModelEffect constant;
    constant.term = steady;
    constant.prior_sigma[0] = e.prior_sigma[0];
    model.effects.push_back(constant);
  }
  const std::string unit(f.term.family->unit);
  // The start value is the model's state (WarmUpEstimates); τ is the scan's.
  ParameterEstimate tau;
  tau.name = TimeConstantName(f.term);
  tau.value = f.time_constant_s;
  tau.method = EstimationMethod::kMaximumLikelihood;
  tau.unit.assign(1, 's');  // seconds
  identified.push_back(std::move(tau));
  notes.push_back(absl::StrFormat(
      "%s: the bias settles by about %.3g %s from the run's start with τ %.0f s (2Δℓ = %.1f over %d time "
      "constants, p = %.2g): a warm-up, carried in the model so that the start is not taken for a fault",
      f.term.Name(), f.estimate, unit, f.time_constant_s, f.statistic, f.time_constants_tried, f.p_value));
}


}  // namespace

int AddTheWarmUpsTheRunShows(const RunContext& c, ErrorModel& model, std::vector<ParameterEstimate>& identified,
                             std::vector<std::string>& notes) {
  int added = 0;
  // Each round adds what stands beside the warm-ups already in the model;
  // there are six axes.
  for (int round = 0; round < kSensorAxisCount; ++round) {
    auto fits = ScanWarmUps(c.epochs, model, WarmUpGrid{});
    if (!fits.ok()) {
      notes.push_back(absl::StrCat("no scan for warm-ups: ", fits.status().message()));
      break;
    }
    // One at a time, the strongest first: two axes' warm-ups can carry one
    // signal (on a level unit at rest every accelerometer's reaches the
    // vertical channel), and the one added takes it from the others.
    const std::vector<const WarmUpFit*> found = Significant(*fits, c.options.finder.family_wise_alpha);
    if (found.empty()) break;
    const WarmUpFit* strongest = *std::max_element(
        found.begin(), found.end(), [](const WarmUpFit* a, const WarmUpFit* b) { return a->statistic < b->statistic; });
    AddWarmUp(*strongest, c.options, model, identified, notes);
    ++added;
  }
  return added;
}

}  // namespace insdiag::engine::pipeline
