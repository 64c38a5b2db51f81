// How the process allocates the analysis's large buffers.
//
// A filter pass that keeps what the smoother needs stores about 9 kB an
// epoch (filter/forward_filter.h: the transition and the packed predicted and
// filtered covariances), 90 MB for the 10,000 epochs of a 2.8-hour run, and an
// analysis runs hundreds of passes. glibc serves a block above its mmap
// threshold (128 kB, adapting up to 32 MB) from fresh pages and unmaps it when
// freed, so every pass faulted each page of its storage in again: page faults
// and the allocator took half the time of a 1M-sample analysis
// (docs/PERFORMANCE.md, "Large buffers kept for reuse"). Keeping freed blocks
// in the heap lets the next pass reuse the pages; the peak memory is the same.
#pragma once

namespace insdiag::engine::numerics {

// Raises the allocator's mmap and trim thresholds for the whole process, once
// (later calls do nothing); a no-op where the C library is not glibc.
void KeepLargeBuffersForReuse();

}  // namespace insdiag::engine::numerics
