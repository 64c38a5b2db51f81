// An identified parameter of the error model, as the report lists it.
#pragma once

#include <limits>
#include <string>

namespace insdiag::engine {

// An identified parameter of the error model.
struct ParameterEstimate {
  std::string name;  // "gyro_bias_gm.x.sigma", "gyro_arw.x", "gyro_scale_factor.z", …
  double value = 0.0;
  double std_error = std::numeric_limits<double>::quiet_NaN();
  std::string method;  // "ACF", "ALLAN", "FILTER", "ML" (innovation likelihood) or "STATIC" (static means)
  std::string unit;
  double a_priori = std::numeric_limits<double>::quiet_NaN();  // the model's value before identification
  // 95% interval (NaN when the estimator gives none beyond ± 1.96 σ).
  double ci95_low = std::numeric_limits<double>::quiet_NaN();
  double ci95_high = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace insdiag::engine
