#include "insdiag/engine/finder/raw_sample_evidence.h"

#include <absl/strings/str_format.h>

#include <algorithm>
#include <cmath>

#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine {
namespace {

bool IsConstantBias(const EffectFamily& family) {
  return family.kind == EffectKind::kConstant && family.regressor == Regressor::kOne;
}

bool HoldsDeterministicEffectOf(const ErrorModel& model, Sensor sensor) {
  return std::ranges::any_of(model.effects, [&](const ModelEffect& e) {
    return e.term.family->sensor == sensor && e.term.family->kind != EffectKind::kRandom;
  });
}

}  // namespace

std::vector<RawSampleConstant> RawConstantsComparable(const RawSampleEvidence& evidence,
                                                      const ErrorModel& model) {
  std::vector<RawSampleConstant> out;
  for (const RawSampleConstant& c : evidence.constants) {
    if (!HoldsDeterministicEffectOf(model, c.sensor)) out.push_back(c);
  }
  return out;
}

bool RefutedByRawSamples(const EffectTerm& term, double estimate, double std_error,
                         std::span<const RawSampleConstant> constants, double family_wise_alpha,
                         std::string* note) {
  if (!IsConstantBias(*term.family) || constants.empty() || !std::isfinite(estimate) ||
      !(std_error > 0.0)) {
    return false;
  }
  const auto of_axis = std::ranges::find_if(constants, [&](const RawSampleConstant& c) {
    return c.sensor == term.family->sensor && c.axis == term.axis;
  });
  if (of_axis == constants.end() || !(of_axis->std_error > 0.0)) return false;
  const double z = (estimate - of_axis->bias) / std::hypot(std_error, of_axis->std_error);
  const double bound = stats::NormalQuantile(
      1.0 - family_wise_alpha / (2.0 * static_cast<double>(constants.size())));
  if (!(std::abs(z) > bound)) return false;
  if (note != nullptr) {
    *note = absl::StrFormat(
        "refuted by the raw samples of the still segments, which put this constant at %.3g ± %.2g "
        "%s "
        "(%.1f standard errors from the estimate; bound %.1f): its signature here comes from "
        "another effect",
        of_axis->bias, of_axis->std_error, term.family->unit, std::abs(z), bound);
  }
  return true;
}

}  // namespace insdiag::engine
