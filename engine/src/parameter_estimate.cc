#include "insdiag/engine/parameter_estimate.h"

#include <cmath>

#include <array>
#include <utility>

namespace insdiag::engine {
namespace {

constexpr std::array<std::pair<EstimationMethod, std::string_view>, 5> kMethodNames = {{
    {EstimationMethod::kAutocorrelation, "ACF"},
    {EstimationMethod::kAllan, "ALLAN"},
    {EstimationMethod::kFilterState, "FILTER"},
    {EstimationMethod::kMaximumLikelihood, "ML"},
    {EstimationMethod::kStaticMeans, "STATIC"},
}};

}  // namespace

std::string_view MethodName(EstimationMethod method) {
  for (const auto& [m, name] : kMethodNames) {
    if (m == method) return name;
  }
  return "";
}

std::optional<EstimationMethod> MethodNamed(std::string_view name) {
  for (const auto& [m, text] : kMethodNames) {
    if (text == name) return m;
  }
  return std::nullopt;
}

bool ObservableByRun(const ParameterEstimate& p) {
  if (std::abs(p.max_correlation) > kSeparableCorrelation) return false;
  if (std::isinf(p.prior_std)) return false;  // the test never excited it
  if (!(p.prior_std > 0.0) || !std::isfinite(p.std_error)) return true;
  return p.std_error < kObservableStdFraction * p.prior_std;
}

}  // namespace insdiag::engine
