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
#include "insdiag/engine/finder/onset_scan.h"
#include "insdiag/engine/finder/score_test.h"
#include "insdiag/engine/ident/retarget.h"
#include "insdiag/engine/model/state_layout.h"
#include "insdiag/engine/monitor/live_monitor.h"
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

ErrorModel NavigationGradeBaseModel() {
  ErrorModel m;
  for (auto& b : m.gyro.bias) b = {0.01 * kDeg / 3600.0, 1800.0};
  for (auto& b : m.acc.bias) b = {30e-6 * 9.80665, 1800.0};
  m.gyro.white_noise_density.setConstant(0.002 * kDeg / 60.0);
  m.acc.white_noise_density.setConstant(10e-6 * 9.80665);
  m.reference = AnalysisOptions{}.reference;
  return m;
}

// The sweep over the samples that condenses a run to its update epochs
// (mechanisation, couplings, the pilot filter): once per analysis.
void BM_CondenseRun(benchmark::State& state) {
  BenchRun hour = HourRun("rotations").run;
  hour.samples.resize(std::min<size_t>(hour.samples.size(), 360000));
  const ErrorModel m = NavigationGradeBaseModel();
  double bytes_per_epoch = 0.0;
  for (auto _ : state) {
    auto epochs = CondenseRun(hour, m, FilterOptions{}.update_interval_s);
    bytes_per_epoch = epochs->BytesPerEpoch();
    benchmark::DoNotOptimize(epochs);
  }
  state.counters["stored_bytes_per_epoch"] = bytes_per_epoch;
}
BENCHMARK(BM_CondenseRun)->Unit(benchmark::kMillisecond);

// A test monitored while it is recorded (monitor/live_monitor.h): the same
// hour arriving in one-second chunks, condensed, filtered, tested and
// scanned for steps as it comes. Beside BM_CondenseRun (the same sweep over
// a complete run), its cost is the live monitor's own: the innovation tests
// and the step scan's window of onsets.
void BM_LiveMonitor(benchmark::State& state) {
  const BenchRun& source = HourRun("rotations").run;
  const size_t samples = std::min<size_t>(source.samples.size(), 360000);
  const ErrorModel m = NavigationGradeBaseModel();
  LiveMonitorOptions options;
  options.planned_duration_s = 3600.0;
  for (auto _ : state) {
    BenchRun growing;
    growing.metadata = source.metadata;
    growing.samples.reserve(samples);
    auto live = LiveMonitor::Create(growing, m, options);
    for (size_t next = 0; next < samples; next += 100) {
      growing.samples.insert(growing.samples.end(), source.samples.begin() + static_cast<long>(next),
                             source.samples.begin() + static_cast<long>(std::min(samples, next + 100)));
      benchmark::DoNotOptimize((*live)->Advance());
    }
    benchmark::DoNotOptimize((*live)->Finish());
  }
  state.counters["samples_per_s"] =
      benchmark::Counter(static_cast<double>(samples), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_LiveMonitor)->Unit(benchmark::kMillisecond);

// One model's filter pass over the condensed run: what every identification
// step, structure test and model comparison costs. With state.range(0) = 1
// also the one-pass score test of every absent catalogue effect (the
// missing-effect scan).
void BM_ForwardFilter(benchmark::State& state) {
  const bool with_scan = state.range(0) != 0;
  BenchRun hour = HourRun("rotations").run;
  hour.samples.resize(std::min<size_t>(hour.samples.size(), 360000));
  const ErrorModel m = NavigationGradeBaseModel();
  const StateLayout layout(m);
  const auto epochs = CondenseRun(hour, m, FilterOptions{}.update_interval_s);
  const int segment_epochs = static_cast<int>(AnalysisOptions{}.segment_s / FilterOptions{}.update_interval_s);
  double bytes_per_sample = 0.0;
  size_t candidates = 0;
  for (auto _ : state) {
    std::unique_ptr<ScoreTestObserver> scan;
    if (with_scan) scan = std::make_unique<ScoreTestObserver>(layout, *epochs, AbsentConstantCandidates(m), segment_epochs);
    auto fw = RunForwardFilter(*epochs, m, scan.get());
    bytes_per_sample = fw->BytesPerSample(hour.samples.size());
    candidates = scan ? scan->columns().size() : 0;
    benchmark::DoNotOptimize(fw);
  }
  state.counters["stored_bytes_per_sample"] = bytes_per_sample;
  state.counters["candidate_columns"] = static_cast<double>(candidates);
}
BENCHMARK(BM_ForwardFilter)->ArgName("scan")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// The bias step and ramp scan over every onset of every sensor axis (one
// backward sweep over a stored filter pass): beside BM_ForwardFilter/scan:0,
// the cost of a base pass.
// One filter pass of the navigation-grade base model over the hour of `rotations`.
struct BasePassOfTheHour {
  BasePassOfTheHour() : hour(HourRun("rotations").run), model(NavigationGradeBaseModel()), layout(model) {
    hour.samples.resize(std::min<size_t>(hour.samples.size(), 360000));
    epochs = *CondenseRun(hour, model, FilterOptions{}.update_interval_s);
    forward = *RunForwardFilter(epochs, model);
  }
  BenchRun hour;
  const ErrorModel model;
  const StateLayout layout;
  EpochRun epochs;
  ForwardPass forward;
};

void BM_OnsetScan(benchmark::State& state) {
  const BasePassOfTheHour base;
  const std::vector<EffectTerm> terms = AbsentFaultTerms(base.model);
  for (auto _ : state) {
    benchmark::DoNotOptimize(ScanOnsets(base.forward, base.layout, base.epochs, terms, OnsetScanOptions{}));
  }
  state.counters["fault_terms"] = static_cast<double>(terms.size());
  state.counters["epochs"] = static_cast<double>(base.epochs.size());
}
BENCHMARK(BM_OnsetScan)->Unit(benchmark::kMillisecond);

// Correlation processing of the six smoothed drifts of one pass (every
// missing-effect scan runs it): the families' fits to the sample
// autocovariance (INSDIAG_THREADS=1 times one core), against
// BM_ForwardFilter/scan:0.
void BM_CorrelateDrifts(benchmark::State& state) {
  const BasePassOfTheHour base;
  const ident::CorrelationOptions options;
  const auto sm =
      RunSmoother(base.forward, ident::DriftSmootherOptions(base.model, base.layout, base.forward, options));
  for (auto _ : state) {
    benchmark::DoNotOptimize(ident::CorrelateDrifts(base.forward, *sm, base.layout, options, nullptr));
  }
}
BENCHMARK(BM_CorrelateDrifts)->Unit(benchmark::kMillisecond);

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
