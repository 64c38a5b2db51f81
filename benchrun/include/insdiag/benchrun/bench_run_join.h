// Joining the files of a multi-position test — static positions and turns
// recorded one after another, with unrecorded moves between them — into one
// bench run of segments (format version 2, docs/MULTI_POSITION.md); what
// `insdiag join` does.
#pragma once

#include <absl/status/statusor.h>

#include <filesystem>
#include <vector>

#include "insdiag/engine/bench_run.h"

namespace insdiag::benchrun {

// Reads the files and joins them: each file becomes a segment (its own
// segments, if it has any, stay segments), in the order given; the files must
// be of one unit at one site with one sample interval and alike in carrying
// temperature. Each file's times are moved to start one interval after the
// previous file's end. The joined run has format 2 and `joined_from` naming
// the files. A file that cannot be read, or does not fit the first, is
// refused with its path and the field that differs.
absl::StatusOr<engine::BenchRun> JoinBenchRunFiles(const std::vector<std::filesystem::path>& files);

}  // namespace insdiag::benchrun
