#include "number_text.h"

#include "insdiag/benchrun/numbers.h"

#include <absl/strings/str_format.h>

#include <charconv>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <system_error>
#include <type_traits>

namespace insdiag::benchrun::internal {
namespace {

constexpr long double kRadiansPerDegree = std::numbers::pi_v<long double> / 180.0L;

template <typename Real>
NumberParse ParseWhole(std::string_view text, Real& value) {
  // from_chars refuses a leading '+', which spreadsheet exports sometimes write.
  if (text.size() > 1 && text.front() == '+' && text[1] != '-' && text[1] != '+') {
    text.remove_prefix(1);
  }
  // libstdc++ 12 parses a long double with strtold on the caller's buffer,
  // which reads to a NUL past the view's end (found by the CSV fuzzer, an
  // ASan heap overflow): long doubles get a terminated copy. Only metadata
  // values are long double; samples parse as double in place.
  std::string terminated;
  if constexpr (std::is_same_v<Real, long double>) {
    terminated.assign(text);
    text = terminated;
  }
  const char* const end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ptr != end || ec == std::errc::invalid_argument) return NumberParse::kNotANumber;
  if (ec == std::errc::result_out_of_range) return NumberParse::kOutOfRange;
  if (!std::isfinite(value)) return NumberParse::kNotFinite;
  return NumberParse::kOk;
}

}  // namespace

NumberParse ParseDouble(std::string_view text, double& value) { return ParseWhole(text, value); }

NumberParse ParseDegreesAsRadians(std::string_view text, double& radians) {
  long double degrees = 0.0L;
  const NumberParse outcome = ParseWhole(text, degrees);
  if (outcome != NumberParse::kOk) return outcome;
  radians = static_cast<double>(degrees * kRadiansPerDegree);
  if (!std::isfinite(radians)) return NumberParse::kOutOfRange;
  return NumberParse::kOk;
}

std::string DescribeNumberParse(NumberParse outcome, std::string_view text) {
  std::string_view what = "is out of the range of a double";
  switch (outcome) {
    case NumberParse::kOk:
      what = "is a number";
      break;
    case NumberParse::kNotANumber:
      what = "is not a number";
      break;
    case NumberParse::kNotFinite:
      what = "is not a finite number";
      break;
    case NumberParse::kOutOfRange:
      break;
  }
  return absl::StrFormat("'%s' %s", text, what);
}

std::string ShortestText(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

std::string DegreesText(double radians) {
  const long double degrees = static_cast<long double>(radians) / kRadiansPerDegree;
  // `degrees` is within a few long-double ulps of the exact preimage, so its
  // shortest text reads back to it and degrees × π/180 rounds to `radians`
  // (the error is far below half a double ulp). Shorter texts usually do too:
  // a site written as 55.5672 should come back as 55.5672, so try roundings to
  // fewer significant digits first.
  char buffer[64];
  for (int digits = 1; digits < std::numeric_limits<long double>::max_digits10; ++digits) {
    const auto rounded =
        std::to_chars(buffer, buffer + sizeof buffer, degrees, std::chars_format::general, digits);
    const std::string_view text(buffer, static_cast<std::size_t>(rounded.ptr - buffer));
    double read_back = 0.0;
    if (ParseDegreesAsRadians(text, read_back) == NumberParse::kOk && read_back == radians) {
      return std::string(text);
    }
  }
  const auto shortest = std::to_chars(buffer, buffer + sizeof buffer, degrees);
  return std::string(buffer, shortest.ptr);
}

double DegreesFromRadians(double radians) {
  return static_cast<double>(static_cast<long double>(radians) / kRadiansPerDegree);
}

}  // namespace insdiag::benchrun::internal

namespace insdiag::benchrun {

std::optional<double> FiniteNumber(std::string_view text) {
  double value = 0.0;
  if (internal::ParseDouble(text, value) != internal::NumberParse::kOk) return std::nullopt;
  return value;
}

std::optional<double> SiteAngleRadians(std::string_view degrees_text) {
  double radians = 0.0;
  if (internal::ParseDegreesAsRadians(degrees_text, radians) != internal::NumberParse::kOk) return std::nullopt;
  return radians;
}

}  // namespace insdiag::benchrun
