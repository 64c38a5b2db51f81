#include "insdiag/engine/numerics/large_buffers.h"

#include <mutex>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace insdiag::engine::numerics {

void KeepLargeBuffersForReuse() {
  static std::once_flag once;
  std::call_once(once, [] {
#if defined(__GLIBC__)
    // Above any one buffer of a pass (a 1M-sample run's largest is ~40 MB):
    // blocks come from the heap, and freed ones stay there.
    constexpr int kThresholdBytes = 1 << 30;
    mallopt(M_MMAP_THRESHOLD, kThresholdBytes);
    mallopt(M_TRIM_THRESHOLD, kThresholdBytes);
#endif
  });
}

}  // namespace insdiag::engine::numerics
