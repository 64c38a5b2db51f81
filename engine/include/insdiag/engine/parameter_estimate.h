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
  // A filter state's diffuse prior standard deviation on the excitation the
  // table gave (infinite where it gave none; NaN for other methods): what the
  // run is judged against (ObservableByRun).
  double prior_std = std::numeric_limits<double>::quiet_NaN();
  // A constant filter state's largest posterior correlation with another
  // constant state, and that state's name: ±1 means the run tells only a combination
  // of the two (NaN and empty for other methods).
  double max_correlation = std::numeric_limits<double>::quiet_NaN();
  std::string correlated_with;
  // A drift's σ and τ identified together by likelihood: the other one's
  // name, and the correlation of the two estimates' log errors from their
  // joint observed information. Over a run of a few correlation times the
  // two trade along a ridge (ρ near +1), so only the pair says how far the
  // drift is from another (NaN and empty for every other estimate).
  std::string jointly_with;
  double log_correlation = std::numeric_limits<double>::quiet_NaN();
};

// A filter-estimated parameter is observable from the run when the run's
// data cut its standard deviation to below this fraction of the prior's, and
// the run tells it apart from every other constant: its posterior
// correlation with each stays within ±kSeparableCorrelation. Otherwise its
// estimate is mostly the prior, or only a combination with another state is
// known (a scale factor of an axis that saw one force only is inseparable
// from that axis's bias: s·f + b with f constant). The degree of
// observability as the ratio of posterior to prior standard deviation, and
// separability by correlation: Ham & Brown, IEEE Trans. AES 19(2), 1983.
inline constexpr double kObservableStdFraction = 0.5;
inline constexpr double kSeparableCorrelation = 0.99;

// False for a filter estimate that fails either test above; true when there
// is nothing to judge by (other methods).
bool ObservableByRun(const ParameterEstimate& p);

}  // namespace insdiag::engine
