// A string as JSON, for JSON written outside a message (stored metadata, log
// lines); messages go through json.h.
#pragma once

#include <string>
#include <string_view>

namespace insdiag::api {

// `text` as a JSON string, quotes included: the quote, the backslash and
// control characters escaped (RFC 8259 §7); UTF-8 passes as it is.
std::string JsonString(std::string_view text);

}  // namespace insdiag::api
