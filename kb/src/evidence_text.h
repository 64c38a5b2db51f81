// Numbers in the diagnosis's evidence lines.
#pragma once

#include <absl/strings/str_format.h>

#include <string>

namespace insdiag::kb::internal {

// Three significant figures: "1.45e-07", "1.8e+03".
inline std::string Format(double v) { return absl::StrFormat("%.3g", v); }

// Signed, two significant figures: "+3.5", "-0.41".
inline std::string SignedFormat(double v) { return absl::StrFormat("%+.2g", v); }

}  // namespace insdiag::kb::internal
