// Synthetic bench runs for tests: a level, static unit at a fixed site, the
// gyros sensing Earth rate and the accelerometers gravity, plus white noise
// from a seeded generator. Plausible enough for storage and transport tests;
// not a simulation (see `insdiag simulate`).
#pragma once

#include <cstddef>
#include <cstdint>

#include "insdiag/engine/bench_run.h"

namespace insdiag::testing {

engine::BenchRun SyntheticStaticRun(std::size_t sample_count, double rate_hz, std::uint32_t seed,
                                    bool with_temperature = true);

}  // namespace insdiag::testing
