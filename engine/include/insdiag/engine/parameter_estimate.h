// An identified parameter of the error model, as the report lists it.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <string_view>

namespace insdiag::engine {

// How a parameter was estimated.
enum class EstimationMethod {
  kAutocorrelation,    // a fit of the smoothed estimates' autocorrelation (correlation processing)
  kAllan,              // the Allan variance of the static segments
  kFilterState,        // a state of the filter, its smoothed value at the end
  kMaximumLikelihood,  // the innovations' likelihood
  kStaticMeans,        // the static segments' means against the reference
};

// The method's name in reports and on the API: "ACF", "ALLAN", "FILTER",
// "ML", "STATIC".
std::string_view MethodName(EstimationMethod method);
// The method of a name MethodName gives; nullopt for any other text.
std::optional<EstimationMethod> MethodNamed(std::string_view name);

// An identified parameter of the error model.
struct ParameterEstimate {
  std::string name;  // "gyro_bias_gm.x.sigma", "gyro_arw.x", "gyro_scale_factor.z", …
  double value = 0.0;
  double std_error = std::numeric_limits<double>::quiet_NaN();
  std::optional<EstimationMethod> method;  // none: not stated (an estimate read from elsewhere)
  std::string unit;
  double a_priori = std::numeric_limits<double>::quiet_NaN();  // the model's value before identification
  // 95% interval (NaN when the estimator gives none beyond ± 1.96 σ).
  double ci95_low = std::numeric_limits<double>::quiet_NaN();
  double ci95_high = std::numeric_limits<double>::quiet_NaN();
  // A filter state's prior standard deviation (NaN for other methods): what
  // the model knew of the parameter before this run.
  double prior_std = std::numeric_limits<double>::quiet_NaN();
};

// A filter-estimated parameter is observable from the run when the run's
// data cut its standard deviation to below this fraction of the prior's:
// otherwise its estimate is mostly the prior, whatever the run held (a scale
// factor of an axis that never saw a force, a bias inseparable from a scale
// factor on an axis that saw one force only).
inline constexpr double kObservableStdFraction = 0.5;

// False only for a filter estimate whose standard error stays above
// kObservableStdFraction of its prior's; true when there is no prior to judge by.
bool ObservableByRun(const ParameterEstimate& p);

}  // namespace insdiag::engine
