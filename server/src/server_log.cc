#include "insdiag/server/server_log.h"

#include <absl/strings/str_cat.h>
#include <absl/time/clock.h>
#include <absl/time/time.h>

#include <atomic>
#include <cstdio>
#include <mutex>
#include <string>

#include "insdiag/api/json.h"

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

}  // namespace

void SetLogFormat(LogFormat f) { format.store(f); }

void Log(LogLevel level, std::string_view message) {
  std::string line;
  if (format.load() == LogFormat::kJson) {
    line = absl::StrCat("{\"time\":\"", absl::FormatTime("%Y-%m-%dT%H:%M:%E3SZ", absl::Now(), absl::UTCTimeZone()),
                        "\",\"level\":\"", std::string(LevelName(level)), "\",\"message\":", api::JsonString(message),
                        "}\n");
  } else {
    line = absl::StrCat("insdiagd: ", level == LogLevel::kWarning ? "WARNING: " : "", std::string(message), "\n");
  }
  std::lock_guard lock(write_mutex);
  std::fwrite(line.data(), 1, line.size(), stderr);
  std::fflush(stderr);
}

}  // namespace insdiag::server
