// Limits of the API that its clients check too, so that the CLI refuses what
// the server would, before sending (docs/API.md, "Limits").
#pragma once

namespace insdiag::api {

// A token expires at most this long after it is made: ten years outlasts any
// bench or script it is made for, and a bound keeps the expiry within what
// PostgreSQL's timestamps hold.
inline constexpr int kMaxTokenLifetimeDays = 3650;

}  // namespace insdiag::api
