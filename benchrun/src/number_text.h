// Numbers as the bench-run text holds them: '.' decimal point, no NaN or
// infinity; doubles written in shortest round-trip form.
//
// Site angles are degrees in the text and radians in the value. Parsing them
// goes through long double (64-bit mantissa on x86-64) so that every double of
// radians has a degrees text that reads back to it exactly; the writer looks
// for the shortest such text.
#pragma once

#include <string>
#include <string_view>

namespace insdiag::benchrun::internal {

enum class NumberParse { kOk, kNotANumber, kNotFinite, kOutOfRange };

// Parses the whole of `text` (an optional leading '+' allowed) into `value`.
NumberParse ParseDouble(std::string_view text, double& value);
NumberParse ParseDegreesAsRadians(std::string_view text, double& radians);

// "'abc' is not a number", "'nan' is not a finite number", ...
std::string DescribeNumberParse(NumberParse outcome, std::string_view text);

// Shortest text that reads back to `value`.
std::string ShortestText(double value);
// Shortest degrees text that ParseDegreesAsRadians reads back to `radians`.
std::string DegreesText(double radians);

double DegreesFromRadians(double radians);

}  // namespace insdiag::benchrun::internal
