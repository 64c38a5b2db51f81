// Speed of the bench-run CSV reader and writer on a 1-hour 50 Hz run
// (180,000 rows, ~27 MB, numbers written like the factory exports: 10
// significant digits). The server must parse such a run well under a second.
// And the metadata: reading free keys is linear in their number (a hash set
// finds duplicates), and a metadata bomb of 1k to 100k keys is refused at the
// first key past the limit, in the same time whatever follows it.
//
//   build/tests/benchmarks/benchrun_parse_benchmark
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "insdiag/benchrun/bench_run_csv.h"

namespace insdiag::benchrun {
namespace {

constexpr int kRows = 180'000;
constexpr double kIntervalS = 0.02;

// A static run with sensor noise and a slow table rotation about z.
const std::string& FactoryText() {
  static const std::string text = [] {
    std::mt19937_64 rng(180000);
    std::normal_distribution<double> noise(0.0, 1.0);
    std::string out =
        "# format: insdiag-bench-run/1\n# unit_serial: INS-2000-0042\n# unit_type: INS-2000\n"
        "# site_latitude_deg: 55.5672\n# site_longitude_deg: 38.15\n# site_height_m: 125.0\n"
        "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,ref_roll,ref_pitch,ref_yaw,temp\n";
    char row[512];
    for (int k = 0; k < kRows; ++k) {
      const double t = kIntervalS * (k + 1);
      const int length = std::snprintf(
          row, sizeof row, "%.2f,%.9e,%.9e,%.9e,%.9e,%.9e,%.9e,%.9f,%.9f,%.9f,%.3f\n", t,
          1e-5 * noise(rng), 1e-5 * noise(rng), 0.1 + 1e-5 * noise(rng), 1e-3 * noise(rng),
          1e-3 * noise(rng), -9.8154 + 1e-3 * noise(rng), 1e-4 * noise(rng), 1e-4 * noise(rng),
          std::remainder(0.1 * t, 2.0 * M_PI), 24.0 + 0.5 * t / 3600.0);
      out.append(row, static_cast<std::size_t>(length));
    }
    return out;
  }();
  return text;
}

void BM_ParseBenchRun(benchmark::State& state) {
  const std::string& text = FactoryText();
  for (auto _ : state) {
    absl::StatusOr<engine::BenchRun> run = ParseBenchRun(text, "factory.csv");
    if (!run.ok()) {
      state.SkipWithError(std::string(run.status().message()).c_str());
      break;
    }
    benchmark::DoNotOptimize(run->samples.data());
  }
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(text.size()));
  state.SetItemsProcessed(state.iterations() * kRows);
}
BENCHMARK(BM_ParseBenchRun)->Unit(benchmark::kMillisecond);

void BM_FormatBenchRun(benchmark::State& state) {
  const absl::StatusOr<engine::BenchRun> run = ParseBenchRun(FactoryText(), "factory.csv");
  if (!run.ok()) {
    state.SkipWithError(std::string(run.status().message()).c_str());
    return;
  }
  std::size_t bytes = 0;
  for (auto _ : state) {
    const std::string text = FormatBenchRun(*run);
    bytes = text.size();
    benchmark::DoNotOptimize(text.data());
  }
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(bytes));
  state.SetItemsProcessed(state.iterations() * kRows);
}
BENCHMARK(BM_FormatBenchRun)->Unit(benchmark::kMillisecond);

// A run with `keys` free metadata lines and a few rows.
std::string RunWithFreeKeys(std::int64_t keys) {
  std::string text =
      "# format: insdiag-bench-run/1\n# unit_serial: INS-2000-0042\n# unit_type: INS-2000\n"
      "# site_latitude_deg: 55.5672\n# site_longitude_deg: 38.15\n# site_height_m: 125.0\n";
  for (std::int64_t k = 0; k < keys; ++k) text += "# note_" + std::to_string(k) + ": bench note " + std::to_string(k) + "\n";
  text += "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,ref_roll,ref_pitch,ref_yaw,temp\n";
  for (int row = 1; row <= 10; ++row) text += std::to_string(0.01 * row) + ",0,0,0,0,0,-9.8154,0,0,0,24\n";
  return text;
}

void BM_ReadFreeMetadata(benchmark::State& state) {
  const std::string text = RunWithFreeKeys(state.range(0));
  for (auto _ : state) {
    absl::StatusOr<engine::BenchRun> run = ParseBenchRun(text, "keys.csv");
    if (!run.ok()) {
      state.SkipWithError(std::string(run.status().message()).c_str());
      break;
    }
    benchmark::DoNotOptimize(run->metadata.extra.data());
  }
  state.SetComplexityN(state.range(0));
}
BENCHMARK(BM_ReadFreeMetadata)->RangeMultiplier(2)->Range(16, kMaxFreeMetadataKeys)->Complexity(benchmark::oN)
    ->Unit(benchmark::kMicrosecond);

void BM_RefuseMetadataBomb(benchmark::State& state) {
  const std::string text = RunWithFreeKeys(state.range(0));
  for (auto _ : state) {
    const absl::Status refused = ParseBenchRun(text, "bomb.csv").status();
    if (refused.ok()) {
      state.SkipWithError("a metadata bomb was read");
      break;
    }
    benchmark::DoNotOptimize(refused);
  }
  state.SetComplexityN(state.range(0));
}
BENCHMARK(BM_RefuseMetadataBomb)->Arg(1'000)->Arg(10'000)->Arg(30'000)->Arg(100'000)->Complexity()
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace insdiag::benchrun

BENCHMARK_MAIN();
