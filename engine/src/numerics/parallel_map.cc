#include "insdiag/engine/numerics/parallel_map.h"

#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <string_view>

namespace insdiag::engine::numerics {

int WorkerThreads() {
  static const int threads = [] {
    if (const char* env = std::getenv("INSDIAG_THREADS"); env != nullptr) {
      const std::string_view text(env);
      int n = 0;
      const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), n);
      if (ec == std::errc() && end == text.data() + text.size() && n > 0) return n;
    }
    return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  }();
  return threads;
}

namespace detail {
bool& InsideParallelMap() {
  thread_local bool inside = false;
  return inside;
}
}  // namespace detail

}  // namespace insdiag::engine::numerics
