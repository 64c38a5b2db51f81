// The warm-up scan (finder/warm_up_scan.h): its score against the filter
// that carries the warm-up as a decaying state, what it finds of a hidden
// warm-up, and its false-alarm rate on healthy units.
#include "insdiag/engine/finder/warm_up_scan.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "insdiag/engine/analysis.h"
#include "insdiag/engine/filter/forward_filter.h"
#include "insdiag/engine/model/parameters.h"
#include "scenarios.h"

namespace insdiag::engine {
namespace {

constexpr double kRunS = 1800.0;
constexpr double kRateHz = 10.0;

// A navigation-grade unit on the short-turns profile, with the warm-up
// `spec` ("acc_warm_up.y=START,TAU_S", insdiag simulate's syntax) if any.
sim::SimulatedRun Simulated(const std::string& spec, uint64_t seed) {
  auto unit = testing::NavigationGradeUnit();
  if (!spec.empty()) {
    auto effects = sim::ParseTrueEffect(spec);
    EXPECT_TRUE(effects.ok()) << effects.status();
    unit.effects = *effects;
  }
  return testing::SimulateOrDie(unit, testing::ShortTurnsProfile(120.0, kRunS), kRateHz, seed);
}

EffectTerm TermOf(const std::string& name) {
  auto terms = ParseEffectSelector(name);
  EXPECT_TRUE(terms.ok() && terms->size() == 1) << name;
  return terms->front();
}

const WarmUpFit& FitOf(const std::vector<WarmUpFit>& fits, const std::string& name) {
  const auto it = std::find_if(fits.begin(), fits.end(), [&](const WarmUpFit& f) { return f.term.Name() == name; });
  EXPECT_NE(it, fits.end()) << name;
  return *it;
}

// With τ fixed, the scan's start value and standard error are those of a
// filter that carries the warm-up as a state decaying with τ from a diffuse
// prior, beside the axis' steady value (its turn-on bias, diffuse too): two
// derivations, the column's second-order expansion and the partial score
// against the states' exact discretisation (model_transitions.h).
TEST(WarmUpScan, EqualsTheFilterThatCarriesTheWarmUpAsAState) {
  auto unit = testing::NavigationGradeUnit();
  const double start = 20.0 * unit.acc.bias[1].sigma, tau_s = 240.0;
  const auto sim = Simulated("acc_warm_up.y=" + std::to_string(start) + "," + std::to_string(tau_s), 3);
  const ErrorModel model = testing::TrueBaseModel(unit);
  auto run = CondenseRun(sim.run, model, 1.0);
  ASSERT_TRUE(run.ok()) << run.status();
  WarmUpScoreObserver observer(StateLayout(model), *run, {tau_s});
  ASSERT_TRUE(RunForwardFilter(*run, model, &observer).ok());
  const WarmUpFit& scanned = FitOf(observer.Fits(model), "acc_warm_up.y");

  ErrorModel with = model;
  ASSERT_TRUE(SetParameter("acc_warm_up.y.tau", tau_s, with).ok());
  ASSERT_TRUE(SetParameter("acc_warm_up.y.prior_sigma", 1e4 * scanned.std_error, with).ok());
  ASSERT_TRUE(SetParameter("acc_turn_on_bias.y.prior_sigma", 1e4 * scanned.std_error, with).ok());
  auto forward = RunForwardFilter(*run, with);
  ASSERT_TRUE(forward.ok()) << forward.status();
  const StateLayout layout(with);
  const int state = layout.EffectOffset(0);
  const int last = forward->epochs() - 1;
  // No process noise: the state at the end is the start value decayed.
  const double decay = std::exp(-(forward->epoch_time_s.back() - forward->epoch_start_s.front()) / tau_s);
  Eigen::MatrixXd P;
  UnpackSymmetric(forward->P_filt.row(last).data(), forward->state_size, P);
  const double filtered = forward->x_filt(last, state) / decay;
  const double filtered_se = std::sqrt(P(state, state)) / decay;
  EXPECT_NEAR(scanned.estimate, filtered, 1e-3 * filtered_se);
  EXPECT_NEAR(scanned.std_error, filtered_se, 1e-3 * filtered_se);
  // The start value is found within its standard error's reach.
  EXPECT_NEAR(scanned.estimate, start, 4.0 * scanned.std_error);
}

// A warm-up of 20 drift σ settling with τ 240 s on one accelerometer: found
// on that axis at the family-wise 1 %, its τ within a factor of 1.5 and its
// start value within 4 standard errors, over five seeds.
TEST(WarmUpScan, FindsAHiddenWarmUpAndItsTimeConstant) {
  auto unit = testing::NavigationGradeUnit();
  const double start = 20.0 * unit.acc.bias[1].sigma, tau_s = 240.0;
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE(seed);
    const auto sim = Simulated("acc_warm_up.y=" + std::to_string(start) + "," + std::to_string(tau_s), seed);
    const ErrorModel model = testing::TrueBaseModel(unit);
    auto run = CondenseRun(sim.run, model, 1.0);
    ASSERT_TRUE(run.ok()) << run.status();
    auto fits = ScanWarmUps(*run, model, WarmUpGrid{});
    ASSERT_TRUE(fits.ok()) << fits.status();
    ASSERT_EQ(fits->size(), 6u);
    const WarmUpFit& f = FitOf(*fits, "acc_warm_up.y");
    EXPECT_LT(f.p_value * 6.0, 0.01);
    EXPECT_GT(f.time_constant_s, tau_s / 1.5);
    EXPECT_LT(f.time_constant_s, tau_s * 1.5);
    EXPECT_NEAR(f.estimate, start, 4.0 * f.std_error + 0.1 * start);
  }
}

// Healthy units: the smallest Bonferroni-adjusted p-value over the six axes
// falls below 1 % in at most 2 of 20 seeds (Davies' bound is conservative:
// at most 0.2 expected; P(≥ 3 of 20) < 0.002 at a true rate of 1 %).
TEST(WarmUpScan, HealthyUnitsRarelyShowOne) {
  auto unit = testing::NavigationGradeUnit();
  const ErrorModel model = testing::TrueBaseModel(unit);
  int alarms = 0;
  double smallest = 1.0;
  for (uint64_t seed = 101; seed <= 120; ++seed) {
    const auto sim = Simulated("", seed);
    auto run = CondenseRun(sim.run, model, 1.0);
    ASSERT_TRUE(run.ok()) << run.status();
    auto fits = ScanWarmUps(*run, model, WarmUpGrid{});
    ASSERT_TRUE(fits.ok()) << fits.status();
    double p = 1.0;
    for (const WarmUpFit& f : *fits) p = std::min(p, f.p_value * static_cast<double>(fits->size()));
    smallest = std::min(smallest, p);
    alarms += p < 0.01 ? 1 : 0;
  }
  EXPECT_LE(alarms, 2) << "smallest adjusted p " << smallest;
}

// The loop on a unit that warms up: the report lists the warm-up with its
// time constant and score, and adding it as the candidate says (name@τ) lets the
// model explain the start: the log-likelihood rises by at least the scan's
// 2Δℓ less a quarter (the model re-estimates what the scan took to first
// order), the warm-up and its axis' steady value are in model B.
TEST(WarmUpScan, AddedAsTheCandidateSaysTheModelExplainsTheStart) {
  auto unit = testing::NavigationGradeUnit();
  const double start = 20.0 * unit.acc.bias[1].sigma, tau_s = 240.0;
  const auto sim = Simulated("acc_warm_up.y=" + std::to_string(start) + "," + std::to_string(tau_s), 2);
  AnalysisRequest request;
  request.nominal = testing::TrueBaseModel(unit);
  auto a = Analyze(sim.run, request, AnalysisOptions{});
  ASSERT_TRUE(a.ok()) << a.status();
  const auto listed = std::find_if(a->report.effect_candidates.begin(), a->report.effect_candidates.end(),
                                   [](const EffectCandidate& c) { return c.name == "acc_warm_up.y"; });
  ASSERT_NE(listed, a->report.effect_candidates.end());
  ASSERT_TRUE(listed->time_constant_s.has_value());
  EXPECT_GT(listed->statistic, 25.0);  // 2Δℓ of 20 drift σ from the start, beyond any noise's reach
  request.add_effects = {"acc_warm_up.y@" + std::to_string(*listed->time_constant_s)};
  auto b = Analyze(sim.run, request, AnalysisOptions{});
  ASSERT_TRUE(b.ok()) << b.status();
  ASSERT_TRUE(b->report.comparison.has_value());
  const ModelComparison& c = *b->report.comparison;
  EXPECT_GT(2.0 * (c.after.log_likelihood - c.before.log_likelihood), 0.75 * listed->statistic);
  EXPECT_GE(b->model.FindEffect(TermOf("acc_warm_up.y")), 0);
  EXPECT_GE(b->model.FindEffect(TermOf("acc_turn_on_bias.y")), 0);
}

}  // namespace
}  // namespace insdiag::engine
