#include "insdiag/engine/filter/linear_range.h"

#include <absl/strings/str_format.h>

#include <cmath>

namespace insdiag::engine {
namespace {

// The first-order attitude model's relative error ψ/2 at which it stops
// describing the filter at all: the dropped term half the kept one (ψ = 1 rad).
constexpr double kLinearModelBreakdown = 0.5;

}  // namespace

LinearRange LinearRangeOf(double peak_attitude_error_rad, double relative_std_error) {
  const double linearisation_error = 0.5 * peak_attitude_error_rad;  // relative, of β̂
  if (linearisation_error > kLinearModelBreakdown) return LinearRange::kFarOutside;
  if (linearisation_error > relative_std_error) return LinearRange::kBeyond;
  return LinearRange::kWithin;
}

double StandardErrorWithLinearisation(double estimate, double std_error,
                                      double peak_attitude_error_rad) {
  return std::hypot(std_error, 0.5 * peak_attitude_error_rad * estimate);
}

std::string LinearRangeNote(LinearRange range, double peak_attitude_error_rad,
                            double relative_std_error) {
  const double linearisation_error = 0.5 * peak_attitude_error_rad;
  switch (range) {
    case LinearRange::kFarOutside:
      return absl::StrFormat(
          "far outside the linear range: the estimate would put the filter %.2g rad off in "
          "attitude, "
          "where the first-order error model is %.0f %% wrong; not a finding (a larger error "
          "elsewhere in the model is the likelier cause)",
          peak_attitude_error_rad, 100.0 * linearisation_error);
    case LinearRange::kBeyond:
      return absl::StrFormat(
          "beyond the linear range: the estimate would put the filter %.2g rad off in attitude; "
          "its error is the first-order model's (about %.0f %%) more than its noise (%.0f %%), "
          "and its test counts both: add it to measure it",
          peak_attitude_error_rad, 100.0 * linearisation_error, 100.0 * relative_std_error);
    case LinearRange::kWithin:
      break;
  }
  return {};
}

}  // namespace insdiag::engine
