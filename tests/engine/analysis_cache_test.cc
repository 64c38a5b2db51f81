// The analysis cache (insdiag/engine/analysis_cache.h): analyses that reuse
// a run's preparation and an earlier Add's model A report exactly what the
// same analyses report from scratch, read the run once, and keep within
// their bound.
#include "insdiag/engine/analysis_cache.h"

#include <google/protobuf/util/message_differencer.h>
#include <gtest/gtest.h>

#include <string>

#include "insdiag/api/report_codec.h"
#include "insdiag/api/unit_types.h"
#include "insdiag/engine/analysis.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/sim/simulator.h"
#include "scenarios.h"

namespace insdiag::engine {
namespace {

constexpr double kRate10Hz = 10.0;
// A gyro torquer's scale factor well outside a navigation-grade unit's
// tolerance (shared/spec/effects.md): an Add of it has a step to show.
constexpr double kHiddenScaleFactor = 300e-6;

std::optional<ErrorModel> Ins2000Nominal() {
  auto type = api::BuiltinUnitType("INS-2000");
  EXPECT_TRUE(type.ok()) << type.status();
  auto model = api::BaseModelOf(*type);
  EXPECT_TRUE(model.ok()) << model.status();
  return *model;
}

AnalysisCacheKeys KeysOf(std::string run, std::string identified_base = "") {
  return {std::move(run), std::move(identified_base)};
}

// Every field of the report, its model A's report and its model, compared.
void ExpectSameAnalysis(const Analysis& got, const Analysis& want) {
  std::string differences;
  google::protobuf::util::MessageDifferencer differ;
  differ.ReportDifferencesToString(&differences);
  EXPECT_TRUE(differ.Compare(api::ToProto(got.report, got.model), api::ToProto(want.report, want.model)))
      << differences;
  ASSERT_EQ(got.base_report.has_value(), want.base_report.has_value());
  if (want.base_report.has_value()) {
    differences.clear();
    EXPECT_TRUE(differ.Compare(api::ToProto(*got.base_report, got.model), api::ToProto(*want.base_report, want.model)))
        << differences;
  }
  EXPECT_EQ(got.series.time_s, want.series.time_s);
  EXPECT_TRUE(got.series.residual == want.series.residual);
}

class AnalysisCacheTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // Ten minutes on a turning table with a gyro scale factor hidden.
    auto unit = testing::NavigationGradeUnit();
    sim::TrueEffect hidden;
    hidden.term = ParseEffectSelector("gyro_scale_factor.z")->front();
    hidden.value[0] = kHiddenScaleFactor;
    unit.effects.push_back(hidden);
    sim_ = testing::SimulateOrDie(unit, testing::ShortTurnsProfile(120.0, 600.0), kRate10Hz, 41);
    request_.nominal = Ins2000Nominal();
    // Model A is the nominal model, and no walk or second-order drift is
    // tested: what is cached does not depend on either, and the tests stay
    // short.
    options_.identify = false;
    options_.test_walks_by_likelihood = false;
    options_.test_second_orders_by_likelihood = false;
  }

  std::function<absl::StatusOr<BenchRun>()> Reader() {
    return [this]() -> absl::StatusOr<BenchRun> {
      ++reads_;
      return sim_.run;
    };
  }

  // Model A as an earlier analysis's report carries it (the server's and
  // `insdiag analyze --base`'s way).
  IdentifiedModel BaseOf(const Analysis& a) {
    auto earlier = api::IdentifiedModelOf(api::ToProto(a.report, a.model));
    EXPECT_TRUE(earlier.ok()) << earlier.status();
    return *earlier;
  }

  sim::SimulatedRun sim_;
  AnalysisRequest request_;
  AnalysisOptions options_;
  int reads_ = 0;
};

TEST_F(AnalysisCacheTest, AddsFromAKeptRunAndModelAReportWhatAnalysesFromScratchReport) {
  AnalysisOptions options = options_;
  options.keep_series = true;
  AnalysisCache cache(size_t{1} << 30);

  auto a = cache.Analyze(KeysOf("run-1"), Reader(), request_, options);
  ASSERT_TRUE(a.ok()) << a.status();
  auto a_alone = Analyze(sim_.run, request_, options);
  ASSERT_TRUE(a_alone.ok()) << a_alone.status();
  ExpectSameAnalysis(*a, *a_alone);

  AnalysisRequest add = request_;
  add.identified_base = BaseOf(*a);
  for (const char* effect : {"gyro_scale_factor.z", "gyro_scale_factor.x"}) {
    SCOPED_TRACE(effect);
    add.add_effects = {effect};
    auto cached = cache.Analyze(KeysOf("run-1", "analysis-1"), Reader(), add, options);
    ASSERT_TRUE(cached.ok()) << cached.status();
    auto alone = Analyze(sim_.run, add, options);
    ASSERT_TRUE(alone.ok()) << alone.status();
    ExpectSameAnalysis(*cached, *alone);
    ASSERT_TRUE(cached->report.comparison.has_value());
  }
  EXPECT_EQ(reads_, 1) << "the run is read once, for the first analysis";
  const AnalysisCache::Counts counts = cache.counts();
  EXPECT_EQ(counts.preparations_made, 1);
  EXPECT_EQ(counts.preparations_reused, 2);
  EXPECT_EQ(counts.models_a_reused, 1) << "the first Add computes model A; the next reuses it";
}

// A server keeps model A while idle: the first Add then reuses it, and
// reports what the Add from scratch reports.
TEST_F(AnalysisCacheTest, AModelAKeptAheadServesTheFirstAdd) {
  AnalysisCache cache(size_t{1} << 30);
  auto a = cache.Analyze(KeysOf("run-1"), Reader(), request_, options_);
  ASSERT_TRUE(a.ok()) << a.status();
  AnalysisRequest add = request_;
  add.identified_base = BaseOf(*a);
  auto kept = cache.KeepModelA(KeysOf("run-1", "analysis-1"), add, options_);
  ASSERT_TRUE(kept.ok()) << kept.status();
  EXPECT_TRUE(*kept);
  EXPECT_FALSE(cache.KeepModelA(KeysOf("run-1"), add, options_).ok()) << "no base named";
  auto unknown = cache.KeepModelA(KeysOf("run-2", "analysis-2"), add, options_);
  ASSERT_TRUE(unknown.ok()) << unknown.status();
  EXPECT_FALSE(*unknown) << "a run the cache does not keep is not read";
  EXPECT_EQ(cache.counts().models_a_reused, 0);

  add.add_effects = {"gyro_scale_factor.z"};
  auto cached = cache.Analyze(KeysOf("run-1", "analysis-1"), Reader(), add, options_);
  ASSERT_TRUE(cached.ok()) << cached.status();
  EXPECT_EQ(cache.counts().models_a_reused, 1);
  auto alone = Analyze(sim_.run, add, options_);
  ASSERT_TRUE(alone.ok()) << alone.status();
  ExpectSameAnalysis(*cached, *alone);
  EXPECT_EQ(reads_, 1);
}

// Another baseline condenses the kept screened run again (the baseline is
// the condensation's pilot); another nominal model prepares it again.
TEST_F(AnalysisCacheTest, OtherAPrioriInputsPrepareTheRunAgain) {
  AnalysisCache cache(size_t{1} << 30);
  ASSERT_TRUE(cache.Analyze(KeysOf("run-1"), Reader(), request_, options_).ok());
  const size_t one_baseline = cache.bytes();
  AnalysisRequest other = request_;
  other.baseline_effects = {"gyro_scale_factor.z"};
  auto condensed_again = cache.Analyze(KeysOf("run-1"), Reader(), other, options_);
  ASSERT_TRUE(condensed_again.ok()) << condensed_again.status();
  auto alone = Analyze(sim_.run, other, options_);
  ASSERT_TRUE(alone.ok()) << alone.status();
  ExpectSameAnalysis(*condensed_again, *alone);
  EXPECT_EQ(reads_, 1);
  EXPECT_EQ(cache.counts().screenings_reused, 1);
  EXPECT_GT(cache.bytes(), one_baseline);
  EXPECT_LT(cache.bytes(), 2 * one_baseline) << "the screened run counted once for both";
  other = request_;
  other.nominal->gyro.bias[0].sigma *= 2.0;
  ASSERT_TRUE(cache.Analyze(KeysOf("run-1"), Reader(), other, options_).ok());
  EXPECT_EQ(reads_, 2);
  EXPECT_EQ(cache.counts().preparations_reused, 0);
  EXPECT_EQ(cache.counts().preparations_made, 2);
}

TEST_F(AnalysisCacheTest, KeepsWithinItsBoundLeastRecentlyUsedLeavingFirst) {
  AnalysisCache measure(size_t{1} << 30);
  ASSERT_TRUE(measure.Analyze(KeysOf("run-1"), Reader(), request_, options_).ok());
  const size_t one_run = measure.bytes();
  ASSERT_GT(one_run, sim_.run.samples.size() * sizeof(ImuSample));

  // Room for one preparation: the second run's pushes the first out.
  AnalysisCache cache(one_run + one_run / 2);
  reads_ = 0;
  for (const char* run : {"run-1", "run-2", "run-1"}) {
    ASSERT_TRUE(cache.Analyze(KeysOf(run), Reader(), request_, options_).ok());
    EXPECT_LE(cache.bytes(), one_run + one_run / 2);
  }
  EXPECT_EQ(reads_, 3);

  // Smaller than one preparation: nothing is kept.
  AnalysisCache too_small(one_run / 2);
  ASSERT_TRUE(too_small.Analyze(KeysOf("run-1"), Reader(), request_, options_).ok());
  EXPECT_EQ(too_small.bytes(), 0u);
}

}  // namespace
}  // namespace insdiag::engine
