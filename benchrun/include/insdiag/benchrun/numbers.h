// Numbers as the bench-run text holds them ('.' decimal point, an optional
// leading '+', no NaN or infinity), for the other inputs that make bench runs
// (imports): they read numbers as the reader does, so that a run they make
// writes and reads back unchanged.
#pragma once

#include <optional>
#include <string_view>

namespace insdiag::benchrun {

// The finite number that is the whole of `text` ("-1.5e-3", "+2"), or nullopt.
std::optional<double> FiniteNumber(std::string_view text);

// The radians of a finite degrees text ("34.246048"), or nullopt. Site
// angles are degrees in the text and radians in the value, read through
// long double so that every double of radians has a degrees text that reads
// back to it (bench_run_csv.h).
std::optional<double> SiteAngleRadians(std::string_view degrees_text);

}  // namespace insdiag::benchrun
