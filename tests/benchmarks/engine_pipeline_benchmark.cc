// The engine on a one-hour, 100 Hz bench run (360,000 samples) with the base
// model: spike screening, mechanisation, forward filter, smoother and
// monitoring — the budget is one second on one core.
//
//   build/tests/benchmarks/engine_pipeline_benchmark --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>

#include "bench_units.h"
#include "insdiag/engine/analysis.h"
#include "insdiag/engine/filter/forward_filter.h"
#include "insdiag/engine/filter/smoother.h"
#include "insdiag/engine/sim/simulator.h"

namespace insdiag::engine {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

const sim::SimulatedRun& HourRun(const std::string& profile) {
  static std::map<std::string, sim::SimulatedRun> runs;
  auto it = runs.find(profile);
  if (it != runs.end()) return it->second;
  auto run = sim::Simulate(bench::NavigationGradeUnit(), *sim::BuiltinProfile(profile), bench::HundredHertz(1));
  return runs.emplace(profile, *std::move(run)).first->second;
}

void BM_AnalyzeBaseModel(benchmark::State& state, const std::string& profile) {
  const BenchRun& run = HourRun(profile).run;
  // One hour of samples.
  BenchRun hour = run;
  hour.samples.resize(std::min<size_t>(hour.samples.size(), 360000));
  for (auto _ : state) {
    auto analysis = Analyze(hour, {}, AnalysisOptions{});
    benchmark::DoNotOptimize(analysis);
    if (!analysis.ok()) state.SkipWithError(std::string(analysis.status().message()).c_str());
  }
  state.counters["samples"] = static_cast<double>(hour.samples.size());
  state.counters["samples_per_s"] =
      benchmark::Counter(static_cast<double>(hour.samples.size()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK_CAPTURE(BM_AnalyzeBaseModel, static_hour, std::string("static"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_AnalyzeBaseModel, rotations_hour, std::string("rotations"))->Unit(benchmark::kMillisecond);

void BM_ForwardFilter(benchmark::State& state) {
  BenchRun hour = HourRun("static").run;
  hour.samples.resize(360000);
  ErrorModel m;
  const auto& u = HourRun("static");
  (void)u;
  for (auto& b : m.gyro.bias) b = {0.01 * kDeg / 3600.0, 1800.0};
  for (auto& b : m.acc.bias) b = {30e-6 * 9.80665, 1800.0};
  m.gyro.white_noise_density.setConstant(0.002 * kDeg / 60.0);
  m.acc.white_noise_density.setConstant(10e-6 * 9.80665);
  m.reference = AnalysisOptions{}.reference;
  double bytes_per_sample = 0.0;
  for (auto _ : state) {
    auto fw = RunForwardFilter(hour, m, FilterOptions{});
    bytes_per_sample = fw->BytesPerSample(hour.samples.size());
    benchmark::DoNotOptimize(fw);
  }
  state.counters["stored_bytes_per_sample"] = bytes_per_sample;
}
BENCHMARK(BM_ForwardFilter)->Unit(benchmark::kMillisecond);

void BM_Smoother(benchmark::State& state) {
  BenchRun hour = HourRun("static").run;
  hour.samples.resize(360000);
  auto analysis = Analyze(hour, {}, AnalysisOptions{});
  auto fw = RunForwardFilter(hour, analysis->model, FilterOptions{});
  for (auto _ : state) {
    auto sm = RunSmoother(*fw);
    benchmark::DoNotOptimize(sm);
  }
}
BENCHMARK(BM_Smoother)->Unit(benchmark::kMillisecond);

void BM_SpikeScreening(benchmark::State& state) {
  BenchRun hour = HourRun("static").run;
  hour.samples.resize(360000);
  for (auto _ : state) {
    BenchRun copy = hour;
    benchmark::DoNotOptimize(ScreenAndRepairSpikes(copy, ScreeningOptions{}));
  }
}
BENCHMARK(BM_SpikeScreening)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace insdiag::engine

BENCHMARK_MAIN();
