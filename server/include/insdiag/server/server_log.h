// insdiagd's log: one line per event on stderr, as text for a terminal
// ("insdiagd: message") or, with --log-format json, as one JSON object per
// line for a log collector:
//   {"time":"2026-11-25T23:10:04.123Z","level":"info","message":"…"}
// Lines from several threads never interleave.
#pragma once

#include <string_view>

namespace insdiag::server {

enum class LogFormat { kText, kJson };
enum class LogLevel { kInfo, kWarning, kError };

// For the whole process; text until set.
void SetLogFormat(LogFormat format);

void Log(LogLevel level, std::string_view message);

}  // namespace insdiag::server
