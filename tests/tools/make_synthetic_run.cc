// make_synthetic_run OUT.csv [SAMPLES] [RATE_HZ] [SEED]
// Writes a synthetic static bench run (tests/support/synthetic_run.h) for
// ingest measurements and demos; defaults: 180000 samples at 50 Hz (1 hour).
#include <cstdlib>
#include <iostream>
#include <string>

#include "insdiag/benchrun/bench_run_csv.h"
#include "support/synthetic_run.h"

int main(int argc, char** argv) {
  if (argc < 2 || argc > 5) {
    std::cerr << "usage: make_synthetic_run OUT.csv [SAMPLES] [RATE_HZ] [SEED]\n";
    return 2;
  }
  const std::size_t samples = argc > 2 ? std::stoul(argv[2]) : 180'000;
  const double rate_hz = argc > 3 ? std::stod(argv[3]) : 50.0;
  const auto seed = static_cast<std::uint32_t>(argc > 4 ? std::stoul(argv[4]) : 1);
  const auto run = insdiag::testing::SyntheticStaticRun(samples, rate_hz, seed);
  if (auto status = insdiag::benchrun::WriteBenchRunFile(run, argv[1]); !status.ok()) {
    std::cerr << status.message() << "\n";
    return 1;
  }
  return 0;
}
