// Site angles as the bench-run text holds them: degrees in the text, radians
// in the value, read through long double so that every double of radians has
// a degrees text that reads back to it (bench_run_csv.h). Other inputs of
// site angles (imports) read them the same way, so that a run they make
// writes and reads back unchanged.
#pragma once

#include <optional>
#include <string_view>

namespace insdiag::benchrun {

// The radians of a finite degrees text ("34.246048"), or nullopt.
std::optional<double> SiteAngleRadians(std::string_view degrees_text);

}  // namespace insdiag::benchrun
