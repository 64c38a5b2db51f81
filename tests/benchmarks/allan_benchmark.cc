// Allan analysis of a two-hour, 100 Hz static bench run (720,000 samples,
// six channels): static segments, overlapping Allan variance on the log τ
// grid with EDF intervals, and the fit of the IEEE 952 terms with its
// model-based covariance. The curves, the ramp test and the fits are also
// timed alone.
//
//   build/tests/benchmarks/allan_benchmark --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <array>
#include <string>
#include <vector>

#include "bench_units.h"
#include "insdiag/engine/ident/allan.h"
#include "insdiag/engine/sim/simulator.h"

namespace insdiag::engine::ident {
namespace {

using bench::kDeg;

// A navigation-grade unit (the engine tests' INS-2000 class) held still for two hours.
const BenchRun& TwoHourRun() {
  static const BenchRun run = [] {
    sim::TableProfile p;
    p.name = "static-2h";
    p.angular_acceleration_rad_s2 = 10.0 * kDeg;
    p.thermal.ambient_degc = 25.0;
    p.segments = {{sim::TableSegment::Kind::kHold, 7200.0, 0.0, 0.0, 0.0}};
    return sim::Simulate(bench::NavigationGradeUnit(), p, bench::HundredHertz(1))->run;
  }();
  return run;
}

std::vector<std::vector<double>> Channel(const BenchRun& run, int c) {
  std::vector<std::vector<double>> rates(1);
  for (const ImuSample& s : run.samples) rates[0].push_back(c < 3 ? s.gyro_rad_s[c] : s.acc_mps2[c - 3]);
  return rates;
}

// ramp_test:0 leaves the ramp test out (allan.h: Ramps).
void BM_AllanAnalysis(benchmark::State& state) {
  const BenchRun& run = TwoHourRun();
  AllanOptions options;
  if (state.range(0) == 0) options.ramp_alpha = 0.0;
  for (auto _ : state) {
    auto result = AllanAnalysis(run, options);
    benchmark::DoNotOptimize(result);
    if (!result.ok()) state.SkipWithError(std::string(result.status().message()).c_str());
  }
  state.counters["samples"] = static_cast<double>(run.samples.size());
}
BENCHMARK(BM_AllanAnalysis)->ArgName("ramp_test")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_AllanCurves(benchmark::State& state) {
  const BenchRun& run = TwoHourRun();
  const AllanOptions options;
  std::vector<std::vector<std::vector<double>>> channels;
  for (int c = 0; c < 6; ++c) channels.push_back(Channel(run, c));
  const std::vector<int64_t> m = AllanClusterSizes(run.samples.size(), options);
  for (auto _ : state) {
    for (const auto& rates : channels) benchmark::DoNotOptimize(OverlappingAllanCurve(rates, 0.01, m, options));
  }
  state.counters["taus"] = static_cast<double>(m.size());
}
BENCHMARK(BM_AllanCurves)->Unit(benchmark::kMillisecond);

// The ramp test of the six curves (allan.h: Ramps), as one analysis runs it:
// the first channel simulates the rate random walks of its bound, the other
// five share them. Iterations alternate between the run and the run less its
// last sample, so that each simulates once.
void BM_AllanRampTest(benchmark::State& state) {
  const BenchRun& run = TwoHourRun();
  const AllanOptions options;
  std::array<std::vector<std::vector<std::vector<double>>>, 2> channels;
  std::array<std::vector<std::vector<AllanPoint>>, 2> curves;
  for (size_t shorter = 0; shorter < 2; ++shorter) {
    const std::vector<int64_t> m = AllanClusterSizes(run.samples.size() - shorter, options);
    for (int c = 0; c < 6; ++c) {
      std::vector<std::vector<double>> rates = Channel(run, c);
      rates[0].resize(rates[0].size() - shorter);
      curves[shorter].push_back(OverlappingAllanCurve(rates, 0.01, m, options));
      channels[shorter].push_back(std::move(rates));
    }
  }
  size_t iteration = 0;
  for (auto _ : state) {
    const size_t k = iteration++ % 2;
    for (size_t c = 0; c < channels[k].size(); ++c)
      benchmark::DoNotOptimize(RampBeyondNoise(channels[k][c], curves[k][c], options));
  }
}
BENCHMARK(BM_AllanRampTest)->Unit(benchmark::kMillisecond);

void BM_AllanFits(benchmark::State& state) {
  const BenchRun& run = TwoHourRun();
  const AllanOptions options;
  const std::vector<int64_t> m = AllanClusterSizes(run.samples.size(), options);
  const std::vector<size_t> lengths = {run.samples.size()};
  std::vector<std::vector<AllanPoint>> curves;
  for (int c = 0; c < 6; ++c) curves.push_back(OverlappingAllanCurve(Channel(run, c), 0.01, m, options));
  for (auto _ : state) {
    for (auto curve : curves) benchmark::DoNotOptimize(FitAllanCurve(curve, 0.01, lengths, options));
  }
}
BENCHMARK(BM_AllanFits)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace insdiag::engine::ident

BENCHMARK_MAIN();
