#include "insdiag/server/server_log.h"

#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>
#include <absl/time/clock.h>
#include <absl/time/time.h>

#include <atomic>
#include <cstdio>
#include <mutex>
#include <string>

namespace insdiag::server {
namespace {

std::atomic<LogFormat> format{LogFormat::kText};
std::mutex write_mutex;

std::string_view LevelName(LogLevel level) {
  switch (level) {
    case LogLevel::kInfo:
      return "info";
    case LogLevel::kWarning:
      return "warning";
    case LogLevel::kError:
      return "error";
  }
  return "info";
}

// A JSON string's contents (RFC 8259 §7): quote, backslash and control
// characters escaped; UTF-8 passes as it is.
std::string JsonEscaped(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          out += absl::StrFormat("\\u%04x", static_cast<unsigned char>(c));
        } else {
          out += c;
        }
    }
  }
  return out;
}

}  // namespace

void SetLogFormat(LogFormat f) { format.store(f); }

void Log(LogLevel level, std::string_view message) {
  std::string line;
  if (format.load() == LogFormat::kJson) {
    line = absl::StrCat("{\"time\":\"", absl::FormatTime("%Y-%m-%dT%H:%M:%E3SZ", absl::Now(), absl::UTCTimeZone()),
                        "\",\"level\":\"", std::string(LevelName(level)), "\",\"message\":\"", JsonEscaped(message),
                        "\"}\n");
  } else {
    line = absl::StrCat("insdiagd: ", level == LogLevel::kWarning ? "WARNING: " : "", std::string(message), "\n");
  }
  std::lock_guard lock(write_mutex);
  std::fwrite(line.data(), 1, line.size(), stderr);
  std::fflush(stderr);
}

}  // namespace insdiag::server
