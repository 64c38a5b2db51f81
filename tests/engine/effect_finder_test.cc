// Acceptance tests of the missing-effect finder (shared/spec/effects.md):
//   1. one catalogue family hidden in a simulated navigation-grade unit: the
//      base model's scan ranks it first; adding it brings NIS into its band,
//      lowers AIC, and the filter's estimate lies within 3 σ of the truth;
//   2. no hidden effect: nothing significant at the family-wise level over 20
//      seeds (2 in the suite, 20 in the sweep: tests/support/monte_carlo.h);
//   3. two hidden effects: --discover resolves them in two steps.
// Magnitudes of constant effects are multiples of the INS-2000 unit type's
// tolerances (data/unit-types/INS-2000.json); the random-structure effects,
// which the unit type has no tolerance for, are sized against the unit's base
// drift. Every run is seeded. Each scenario prints one row of the matrix in
// docs/EFFECT_FINDER_SCENARIOS.md ("SCENARIO|..." lines).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <optional>
#include <string>
#include <vector>

#include "insdiag/api/report_codec.h"
#include "insdiag/api/unit_types.h"
#include "insdiag/engine/analysis.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/sim/simulator.h"
#include "scenarios.h"
#include "support/monte_carlo.h"

namespace insdiag::engine {
namespace {

constexpr double kFindRate10Hz = 10.0;

const v1::UnitType& Ins2000() {
  static const v1::UnitType type = [] {
    auto t = api::BuiltinUnitType("INS-2000");
    EXPECT_TRUE(t.ok()) << t.status();
    return *t;
  }();
  return type;
}

// The INS-2000 tolerance of one parameter ("gyro_scale_factor.z", "gyro_yaw_harmonic.z.sin").
double Tolerance(const std::string& parameter) {
  for (const auto& p : Ins2000().nominal()) {
    if (p.name() == parameter) return p.tolerance();
  }
  ADD_FAILURE() << "INS-2000 has no tolerance for " << parameter;
  return std::nan("");
}

std::optional<ErrorModel> NominalModel() {
  auto m = api::BaseModelOf(Ins2000());
  EXPECT_TRUE(m.ok()) << m.status();
  return *m;
}

EffectTerm TermOrDie(const std::string& name) {
  auto terms = ParseEffectSelector(name);
  EXPECT_TRUE(terms.ok() && terms->size() == 1) << name;
  return terms->front();
}

// The first identifiable term candidate, or null.
const EffectCandidate* TopTerm(const AnalysisReport& r) {
  for (const EffectCandidate& c : r.effect_candidates) {
    if (c.identifiable) return &c;
  }
  return nullptr;
}

const EffectCandidate* TopFamily(const AnalysisReport& r) {
  for (const EffectCandidate& c : r.family_candidates) {
    if (c.identifiable) return &c;
  }
  return nullptr;
}

// 1-based rank of `term` among the identifiable term candidates (0: absent).
int RankOf(const AnalysisReport& r, const std::string& term) {
  int rank = 0;
  for (const EffectCandidate& c : r.effect_candidates) {
    if (!c.identifiable) continue;
    ++rank;
    if (c.name == term) return rank;
  }
  return 0;
}

const EffectCandidate* CandidateNamed(const AnalysisReport& r, const std::string& name) {
  for (const EffectCandidate& c : r.effect_candidates) {
    if (c.name == name) return &c;
  }
  return nullptr;
}

// Identifiable candidates significant at the family-wise level (terms and families).
std::vector<std::string> Significant(const AnalysisReport& r, double alpha) {
  std::vector<std::string> out;
  for (const auto* list : {&r.effect_candidates, &r.family_candidates}) {
    for (const EffectCandidate& c : *list) {
      if (c.identifiable && c.p_value_holm < alpha) out.push_back(c.name + " (p_holm " + std::to_string(c.p_value_holm) + ")");
    }
  }
  return out;
}

// ---------------------------------------------------------------------------
// 1. One hidden family.

// How the hidden effect is sized.
enum class Size {
  kTolerances,         // constant family: `k` × the term's INS-2000 tolerance
  kWalkOverTau,        // bias_rw: the walk's σ after one base correlation time τ is k × σ_GM (K = k σ_GM / √τ)
  kSecondOrderSigma,   // bias_second_order: σ₂ = k × σ_GM, decay and period below
};

// Second-order drift of the scenarios: a damped oscillation of a DTG's
// rotor/suspension or of a thermal loop, slower than the table's motion
// segments and faster than the base drift's correlation time.
constexpr double kSecondOrderDecayS = 900.0;
constexpr double kSecondOrderPeriodS = 600.0;

struct FamilyCase {
  std::string label;    // gtest name
  std::string term;     // the hidden term
  std::string profile;  // built-in profile that excites it
  Size size = Size::kTolerances;
  double k = 0.0;
  // Whether the run says its attitude is read, where the case fixes it (bench_run.h).
  std::optional<bool> encoders_read = std::nullopt;
};

void PrintTo(const FamilyCase& c, std::ostream* os) { *os << c.term << " on " << c.profile; }

sim::TrueEffect HiddenEffect(const FamilyCase& c, const sim::SimulatedUnit& unit) {
  sim::TrueEffect e;
  e.term = TermOrDie(c.term);
  const SensorTriadModel& triad = e.term.family->sensor == Sensor::kGyro ? unit.gyro : unit.acc;
  const auto& gm = triad.bias[static_cast<size_t>(e.term.axis)];
  switch (c.size) {
    case Size::kTolerances:
      for (int p = 0; p < e.term.family->parameters_per_term; ++p) {
        e.value[static_cast<size_t>(p)] = c.k * Tolerance(e.term.ParameterName(p));
      }
      break;
    case Size::kWalkOverTau:
      e.random_walk_density = c.k * gm.sigma / std::sqrt(gm.tau_s);
      break;
    case Size::kSecondOrderSigma:
      e.second_order_sigma = c.k * gm.sigma;
      e.second_order_alpha_per_s = 1.0 / kSecondOrderDecayS;
      e.second_order_beta_rad_s = 2.0 * std::numbers::pi / kSecondOrderPeriodS;
      break;
  }
  return e;
}

double TruthOf(const sim::TrueEffect& e, int parameter) {
  switch (e.term.family->process) {
    case RandomProcess::kNone:
      return e.value[static_cast<size_t>(parameter)];
    case RandomProcess::kRandomWalk:
      return e.random_walk_density;
    case RandomProcess::kSecondOrderMarkov:
      return e.second_order_sigma;
    case RandomProcess::kDecayFromStart:
      return e.value[0];
  }
  return std::nan("");
}

// A scenario's run: the navigation-grade unit with the case's effect hidden,
// on the case's profile, seed 7.
struct HiddenRun {
  sim::TrueEffect truth;
  sim::SimulatedRun sim;
};
HiddenRun SimulateHidden(const FamilyCase& c) {
  auto unit = testing::NavigationGradeUnit();
  const sim::TrueEffect truth = HiddenEffect(c, unit);
  unit.effects.push_back(truth);
  HiddenRun hidden{truth, testing::SimulateOrDie(unit, testing::BuiltinProfileOrDie(c.profile), kFindRate10Hz, 7)};
  if (c.encoders_read.has_value()) hidden.sim.run.metadata.DeclareAttitudeReadout(*c.encoders_read);
  return hidden;
}

// One analysis of a scenario's run from the nominal model with the case's
// term added: its base report is model A's, as an analysis without the
// request reports it (test BaseReport), its report model B's.
absl::StatusOr<Analysis> AnalyzeAddingTheTerm(const HiddenRun& hidden, const FamilyCase& c,
                                              const AnalysisOptions& options) {
  AnalysisRequest request;
  request.nominal = NominalModel();
  request.add_effects = {c.term};
  return Analyze(hidden.sim.run, request, options);
}

class HiddenFamily : public ::testing::TestWithParam<FamilyCase> {};

TEST_P(HiddenFamily, RankedFirstAndAddingItFitsTheRun) {
  const FamilyCase& c = GetParam();
  const HiddenRun hidden = SimulateHidden(c);
  const sim::TrueEffect& truth = hidden.truth;
  const std::string family(truth.term.family->name);
  AnalysisOptions options;
  const double alpha = options.finder.family_wise_alpha;

  auto b = AnalyzeAddingTheTerm(hidden, c, options);
  ASSERT_TRUE(b.ok()) << b.status();
  ASSERT_TRUE(b->base_report.has_value());
  const AnalysisReport& ra = *b->base_report;
  const AnalysisReport& rb = b->report;
  ASSERT_TRUE(rb.comparison.has_value());

  const EffectCandidate* top = TopTerm(ra);
  const EffectCandidate* top_family = TopFamily(ra);
  ASSERT_NE(top, nullptr) << "no identifiable candidate";
  // Found: the most significant term is the hidden one, or the most
  // significant family is its family and that family's leading term is it.
  const EffectCandidate* leading_in_family = nullptr;
  for (const EffectCandidate& t : ra.effect_candidates) {
    if (t.identifiable && t.family == family) {
      leading_in_family = &t;
      break;
    }
  }
  const bool by_term = top->name == c.term;
  const bool by_family = top_family != nullptr && top_family->name == family && leading_in_family != nullptr &&
                         leading_in_family->name == c.term;
  const EffectCandidate* own = CandidateNamed(ra, c.term);


  // The estimate to check: constant families have the filter's estimate in
  // identified[]; random structures have no state that holds their parameter,
  // so their estimate is the correlation processing's (the candidate's).
  std::string estimate_text;
  const int parameters = truth.term.family->process == RandomProcess::kNone ? truth.term.family->parameters_per_term : 1;
  for (int p = 0; p < parameters; ++p) {
    const double t = TruthOf(truth, p);
    double value = std::nan(""), se = std::nan("");
    if (truth.term.family->process == RandomProcess::kNone) {
      const std::string name = truth.term.ParameterName(p);
      for (const ParameterEstimate& e : rb.identified) {
        if (e.method == EstimationMethod::kFilterState && e.name == name) {
          value = e.value;
          se = e.std_error;
        }
      }
    } else if (own != nullptr) {
      value = own->estimate;
      se = own->std_error;
    }
    EXPECT_TRUE(std::isfinite(se)) << truth.term.ParameterName(p) << ": no standard error";
    EXPECT_LE(std::abs(value - t), 3.0 * se)
        << truth.term.ParameterName(p) << ": estimate " << value << " ± " << se << ", truth " << t;
    char buf[160];
    std::snprintf(buf, sizeof buf, "%s%.3g ± %.2g (truth %.3g)", p == 0 ? "" : "; ", value, se, t);
    estimate_text += buf;
  }

  char row[640];
  std::snprintf(row, sizeof row, "SCENARIO|%s|%s|%s|%s|%d|%s|%.3f → %.3f [%.3f, %.3f]|%.1f → %.1f|%s", c.term.c_str(),
                c.profile.c_str(), top->name.c_str(), (by_term || by_family) ? "yes" : "no", RankOf(ra, c.term),
                estimate_text.c_str(), rb.comparison->before.nis_mean, rb.comparison->after.nis_mean, rb.nis_band_low,
                rb.nis_band_high, rb.comparison->before.aic, rb.comparison->after.aic,
                own != nullptr ? std::to_string(own->p_value_holm).c_str() : "-");
  std::printf("%s\n", row);
  RecordProperty("row", row);

  EXPECT_TRUE(by_term || by_family) << "top term " << top->name << " (p_holm " << top->p_value_holm
                                    << "), top family " << (top_family ? top_family->name : "none");
  EXPECT_LT(top->p_value_holm, alpha);
  EXPECT_GE(rb.fit.nis_mean, rb.nis_band_low);
  EXPECT_LE(rb.fit.nis_mean, rb.nis_band_high);
  EXPECT_LT(rb.comparison->after.aic, rb.comparison->before.aic);
}

INSTANTIATE_TEST_SUITE_P(
    Families, HiddenFamily,
    ::testing::Values(FamilyCase{"GyroTurnOnBias", "gyro_turn_on_bias.x", "full", Size::kTolerances, 3.0},
                      FamilyCase{"GyroScaleFactor", "gyro_scale_factor.z", "rotations", Size::kTolerances, 4.0},
                      FamilyCase{"GyroMisalignment", "gyro_misalignment.xy", "rotations", Size::kTolerances, 4.0},
                      FamilyCase{"GyroGSensitivity", "gyro_g_sensitivity.xz", "positions", Size::kTolerances, 4.0},
                      FamilyCase{"GyroTempCoeff", "gyro_temp_coeff.y", "thermal", Size::kTolerances, 4.0},
                      FamilyCase{"GyroYawHarmonic", "gyro_yaw_harmonic.x", "rotations", Size::kTolerances, 4.0},
                      FamilyCase{"AccTurnOnBias", "acc_turn_on_bias.y", "full", Size::kTolerances, 3.0},
                      FamilyCase{"AccScaleFactor", "acc_scale_factor.x", "positions", Size::kTolerances, 4.0},
                      FamilyCase{"AccMisalignment", "acc_misalignment.yz", "positions", Size::kTolerances, 4.0},
                      FamilyCase{"AccTempCoeff", "acc_temp_coeff.z", "thermal", Size::kTolerances, 4.0},
                      FamilyCase{"AccBiasSecondOrder", "acc_bias_second_order.z", "full", Size::kSecondOrderSigma, 3.0},
                      // With the encoders read (the default on a turning table) this seed's
                      // second-order drift is explained by a re-tuned drift of the same
                      // gyro (ΔBIC -84 against -71): docs/FAULT_SCENARIOS.md, "The
                      // encoders' attitude", gives the rate over seeds.
                      FamilyCase{"GyroBiasSecondOrder", "gyro_bias_second_order.y", "full", Size::kSecondOrderSigma, 3.0,
                                 /*encoders_read=*/false}),
    [](const ::testing::TestParamInfo<FamilyCase>& p) { return p.param.label; });

// A bias random walk, on the eight-hour `drift` profile (a walk as slow as
// the base drift needs several of its correlation times to tell apart): the
// likelihood's walk test finds it significant, its K within 3 SE of the
// truth; adding it fits the run and explains the offset that the same axis'
// turn-on bias would otherwise take. Over one realisation the walk's offset
// from zero looks like a turn-on bias too, so the walk must rank first, or
// second behind exactly that bias.
class HiddenBiasRandomWalk : public ::testing::TestWithParam<FamilyCase> {};

TEST_P(HiddenBiasRandomWalk, FoundByLikelihoodAndAddingItFitsTheRun) {
  const FamilyCase& c = GetParam();
  const std::string turn_on = c.term.substr(0, c.term.find('_')) + "_turn_on_bias" + c.term.substr(c.term.rfind('.'));
  const HiddenRun hidden = SimulateHidden(c);
  const sim::TrueEffect& truth = hidden.truth;
  AnalysisOptions options;
  const double alpha = options.finder.family_wise_alpha;
  auto b = AnalyzeAddingTheTerm(hidden, c, options);
  ASSERT_TRUE(b.ok()) << b.status();
  ASSERT_TRUE(b->base_report.has_value());
  const AnalysisReport& ra = *b->base_report;  // model A's report, as without the request
  const EffectCandidate* walk = CandidateNamed(ra, c.term);
  ASSERT_NE(walk, nullptr) << "the walk was not proposed";
  const int rank = RankOf(ra, c.term);
  const EffectCandidate* top = TopTerm(ra);
  std::printf("SCENARIO|%s|%s|%s|%d|%.3g ± %.2g (truth %.3g)|p_holm %.3g\n", c.term.c_str(), c.profile.c_str(),
              top->name.c_str(), rank, walk->estimate, walk->std_error, truth.random_walk_density, walk->p_value_holm);
  EXPECT_EQ(walk->source, "LIKELIHOOD");
  EXPECT_LT(walk->p_value_holm, alpha);
  // Second behind its constant look-alike, or behind any candidate it ties
  // with: within 2 of predicted ΔBIC the two are not worth telling apart
  // (Kass & Raftery, JASA 90(430), 1995), and a walk's path over hours can
  // look like one jump as much as like a walk.
  const bool tied = rank == 2 && walk->predicted_delta_bic - top->predicted_delta_bic < 2.0;
  EXPECT_TRUE(rank == 1 || (rank == 2 && top->name == turn_on) || tied)
      << "rank " << rank << ", top " << top->name << " (predicted ΔBIC " << top->predicted_delta_bic
      << " against the walk's " << walk->predicted_delta_bic << ")";
  // The likelihood identifies ln K (a scale: its likelihood is near-quadratic
  // there, not in K); the reported SE is the delta method's K·SE(ln K).
  ASSERT_TRUE(std::isfinite(walk->std_error)) << "no standard error";
  const double log_se = walk->std_error / walk->estimate;
  EXPECT_LE(std::abs(std::log(walk->estimate / truth.random_walk_density)), 3.0 * log_se)
      << walk->estimate << " ± " << walk->std_error << ", truth " << truth.random_walk_density;

  const AnalysisReport& rb = b->report;
  ASSERT_TRUE(rb.comparison.has_value());
  std::printf("SCENARIO|%s|NIS %.4f → %.4f [%.4f, %.4f]|AIC %.1f → %.1f\n", c.term.c_str(),
              rb.comparison->before.nis_mean, rb.comparison->after.nis_mean, rb.nis_band_low, rb.nis_band_high,
              rb.comparison->before.aic, rb.comparison->after.aic);
  EXPECT_GE(rb.fit.nis_mean, rb.nis_band_low);
  EXPECT_LE(rb.fit.nis_mean, rb.nis_band_high);
  EXPECT_LT(rb.comparison->after.aic, rb.comparison->before.aic);
  // The model takes the likelihood's K, and reports it.
  const auto k = std::find_if(rb.identified.begin(), rb.identified.end(),
                              [&](const ParameterEstimate& e) { return e.name == c.term + ".density"; });
  ASSERT_NE(k, rb.identified.end());
  EXPECT_EQ(k->method, EstimationMethod::kMaximumLikelihood);
  EXPECT_DOUBLE_EQ(k->value, walk->estimate);
  EXPECT_TRUE(Significant(rb, alpha).empty()) << Significant(rb, alpha).front();
}

INSTANTIATE_TEST_SUITE_P(
    Walks, HiddenBiasRandomWalk,
    ::testing::Values(FamilyCase{"AccBiasRw", "acc_bias_rw.x", "drift", Size::kWalkOverTau, 3.0},
                      FamilyCase{"GyroBiasRw", "gyro_bias_rw.x", "drift", Size::kWalkOverTau, 3.0}),
    [](const ::testing::TestParamInfo<FamilyCase>& p) { return p.param.label; });

// A walk of this size is near what eight hours resolve: over seeds it is
// found on 5 of 7 seeds for x and y and 2 of 7 for z, the heading axis, whose
// excursion looks like a turn-on offset and a wider drift
// (docs/EFFECT_FINDER_SCENARIOS.md, "Walk detection over seeds"). The suite
// asserts the x walks, which the run resolves; z's rate is the figure.

// ---------------------------------------------------------------------------
// 2. No hidden effect.

// With a correct family-wise test each seed has at most α = 1 % chance of
// any significant candidate. The most seeds with one that the count allows
// fails falsely with probability ≤ 2 % at α (over 20 seeds: at most 1, P(count
// ≥ 2) = 1.7 %); more is evidence the test is anti-conservative. The suite
// runs 2 seeds and allows none (P = 2.0 % at α), which catches a family-wise
// rate of 30 % with probability 0.51 and one of 50 % with 0.75; the sweep
// runs 20 (0.97 against 30 %).
TEST(NoHiddenEffect, NothingSignificantAtTheFamilyWiseLevel) {
  const auto unit = testing::NavigationGradeUnit();
  const auto profile = testing::BuiltinProfileOrDie("rotations");
  AnalysisOptions options;
  const double alpha = options.finder.family_wise_alpha;
  constexpr double kFalseFailure = 0.02;
  const int kNullSeeds = insdiag::testing::Runs({.suite = 2, .sweep = 20});
  int with_significant = 0;
  for (int seed = 1; seed <= kNullSeeds; ++seed) {
    const auto sim = testing::SimulateOrDie(unit, profile, kFindRate10Hz, static_cast<uint64_t>(100 + seed));
    AnalysisRequest request;
    request.nominal = NominalModel();
    auto a = Analyze(sim.run, request, options);
    ASSERT_TRUE(a.ok()) << a.status();
    const auto significant = Significant(a->report, alpha);
    const EffectCandidate* top = TopTerm(a->report);
    std::printf("NULL|%d|%s|%.4g|%zu|%.3f\n", 100 + seed, top ? top->name.c_str() : "-", top ? top->p_value_holm : 1.0,
                significant.size(), a->report.fit.nis_mean);
    if (!significant.empty()) {
      ++with_significant;
      for (const auto& s : significant) std::printf("  significant: %s\n", s.c_str());
    }
  }
  const int most = insdiag::testing::MostAlarms(kNullSeeds, alpha, kFalseFailure);
  std::printf("no hidden effect: seeds with a significant candidate %d of %d (at most %d)\n", with_significant, kNullSeeds, most);
  ASSERT_LT(most, kNullSeeds);
  EXPECT_LE(with_significant, most) << with_significant << " of " << kNullSeeds << " seeds";
  RecordProperty("seeds_with_significant", with_significant);
}

// ---------------------------------------------------------------------------
// 3. Two hidden effects, found by discovery.

bool Names(const std::string& step_effect, const std::string& term) {
  if (step_effect == term) return true;
  auto terms = ParseEffectSelector(step_effect);
  if (!terms.ok()) return false;
  for (const EffectTerm& t : *terms) {
    if (t.Name() == term) return true;
  }
  return false;
}

// An analysis with effects added carries model A's report: the one the same
// run gives without the request (the scenario tests above read it instead of
// analysing twice).
TEST(BaseReport, IsTheReportOfTheAnalysisWithoutTheAddedEffects) {
  const auto sim = testing::SimulateOrDie(testing::NavigationGradeUnit(), testing::ShortTurnsProfile(300.0, 900.0),
                                          kFindRate10Hz, 31);
  AnalysisRequest request;
  request.nominal = NominalModel();
  auto alone = Analyze(sim.run, request, AnalysisOptions{});
  ASSERT_TRUE(alone.ok()) << alone.status();
  EXPECT_FALSE(alone->base_report.has_value());
  request.add_effects = {"gyro_scale_factor.z"};
  auto added = Analyze(sim.run, request, AnalysisOptions{});
  ASSERT_TRUE(added.ok()) << added.status();
  ASSERT_TRUE(added->base_report.has_value());
  const AnalysisReport& a = *added->base_report;
  const AnalysisReport& b = alone->report;
  EXPECT_EQ(a.fit.nis_mean, b.fit.nis_mean);
  EXPECT_EQ(a.fit.log_likelihood, b.fit.log_likelihood);
  ASSERT_EQ(a.effect_candidates.size(), b.effect_candidates.size());
  for (size_t i = 0; i < a.effect_candidates.size(); ++i) {
    EXPECT_EQ(a.effect_candidates[i].name, b.effect_candidates[i].name);
    EXPECT_EQ(a.effect_candidates[i].statistic, b.effect_candidates[i].statistic);
  }
  ASSERT_EQ(a.identified.size(), b.identified.size());
  for (size_t i = 0; i < a.identified.size(); ++i) EXPECT_EQ(a.identified[i].value, b.identified[i].value);
  // The request's own report is model B's, not A's.
  EXPECT_NE(added->report.fit.log_likelihood, b.fit.log_likelihood);
}

// Adding an effect to the model an earlier analysis identified, carried
// through its report as the server and `insdiag analyze --base` carry it,
// reports what the whole analysis with the effect added reports: model A's
// identification is the same, so both passes are.
TEST(IncrementalAdd, ReportsWhatTheWholeAnalysisReports) {
  const auto sim = testing::SimulateOrDie(testing::NavigationGradeUnit(), testing::ShortTurnsProfile(300.0, 900.0),
                                          kFindRate10Hz, 32);
  AnalysisRequest request;
  request.nominal = NominalModel();
  auto alone = Analyze(sim.run, request, AnalysisOptions{});
  ASSERT_TRUE(alone.ok()) << alone.status();
  request.add_effects = {"gyro_scale_factor.z"};
  auto whole = Analyze(sim.run, request, AnalysisOptions{});
  ASSERT_TRUE(whole.ok()) << whole.status();

  auto earlier = api::IdentifiedModelOf(api::ToProto(alone->report, alone->model));
  ASSERT_TRUE(earlier.ok()) << earlier.status();
  EXPECT_TRUE(earlier->model == alone->model) << "the report's model is not the model the analysis identified";
  request.identified_base = *earlier;
  auto incremental = Analyze(sim.run, request, AnalysisOptions{});
  ASSERT_TRUE(incremental.ok()) << incremental.status();

  const AnalysisReport& b = whole->report;
  const AnalysisReport& b_again = incremental->report;
  EXPECT_TRUE(incremental->model == whole->model);
  EXPECT_EQ(b_again.fit.log_likelihood, b.fit.log_likelihood);
  EXPECT_EQ(b_again.fit.nis_mean, b.fit.nis_mean);
  ASSERT_TRUE(b_again.comparison.has_value() && b.comparison.has_value());
  EXPECT_EQ(b_again.comparison->before.log_likelihood, b.comparison->before.log_likelihood);
  EXPECT_EQ(b_again.comparison->predicted_lr, b.comparison->predicted_lr);
  ASSERT_EQ(b_again.effect_candidates.size(), b.effect_candidates.size());
  for (size_t i = 0; i < b.effect_candidates.size(); ++i) {
    EXPECT_EQ(b_again.effect_candidates[i].name, b.effect_candidates[i].name);
    EXPECT_EQ(b_again.effect_candidates[i].statistic, b.effect_candidates[i].statistic);
  }
  ASSERT_EQ(b_again.identified.size(), b.identified.size());
  for (size_t i = 0; i < b.identified.size(); ++i) {
    EXPECT_EQ(b_again.identified[i].name, b.identified[i].name);
    EXPECT_EQ(b_again.identified[i].value, b.identified[i].value) << b.identified[i].name;
  }
}

// Model B of an Add of a constant effect takes model A's walk and pair
// outcomes where A's tests found nothing, rather than testing again: an added
// deterministic effect takes residual from a structure and gives it none.
// Over seeds, with a scale factor and a gyro walk hidden, adding the scale
// factor gives the same verdict on every random structure as model B
// testing every axis again. (Half an hour does not tell this walk from a
// wider drift — the walk scenarios above need eight hours — so neither model
// finds it: what is checked is that testing again would decide nothing
// differently, and model A's verdicts on the walk are printed.) The claim
// holds in every run, so one run can refute it: the suite runs one seed
// (two analyses of half an hour), the sweep four.
TEST(SettledStructures, AnAddedConstantLeavesTheStructureVerdictsAsTestingAgainGivesThem) {
  const int kSeeds = insdiag::testing::Runs({.suite = 1, .sweep = 4});
  const FamilyCase scale{"", "gyro_scale_factor.z", "", Size::kTolerances, 4.0};
  const FamilyCase walk{"", "gyro_bias_rw.x", "", Size::kWalkOverTau, 4.0};
  auto unit = testing::NavigationGradeUnit();
  unit.effects = {HiddenEffect(scale, unit), HiddenEffect(walk, unit)};
  int walks_found = 0;
  for (int seed = 0; seed < kSeeds; ++seed) {
    const auto sim = testing::SimulateOrDie(unit, testing::ShortTurnsProfile(300.0, 1800.0), kFindRate10Hz,
                                            static_cast<uint64_t>(100 + seed));
    AnalysisRequest request;
    request.nominal = NominalModel();
    request.add_effects = {scale.term};
    AnalysisOptions settled_options;
    AnalysisOptions retest_options;
    retest_options.retest_settled_structures = true;
    auto settled = Analyze(sim.run, request, settled_options);
    auto retested = Analyze(sim.run, request, retest_options);
    ASSERT_TRUE(settled.ok() && retested.ok()) << settled.status() << retested.status();
    const double alpha = settled_options.finder.family_wise_alpha;
    for (const EffectCandidate& c : retested->report.effect_candidates) {
      if (c.source != "LIKELIHOOD") continue;
      const EffectCandidate* same = CandidateNamed(settled->report, c.name);
      ASSERT_NE(same, nullptr) << c.name;
      EXPECT_EQ(same->SignificantAt(alpha), c.SignificantAt(alpha))
          << "seed " << 100 + seed << ", " << c.name << ": p_holm " << same->p_value_holm << " taken from model A, "
          << c.p_value_holm << " tested again on model B (" << c.note << ")";
    }
    const EffectCandidate* found = CandidateNamed(*retested->base_report, walk.term);
    walks_found += found != nullptr && found->SignificantAt(alpha) ? 1 : 0;
    std::printf("SETTLED|seed %d|walk on model A p_holm %.3g\n", 100 + seed,
                found != nullptr ? found->p_value_holm : 1.0);
  }
  std::printf("SETTLED|walk found on model A in %d of %d\n", walks_found, kSeeds);
}

// The ranking lists every catalogue effect the model lacks, each once — the
// random structures too, with what their test said or why none ran on this
// model — and none the model has.
TEST(Ranking, ListsEveryCatalogueEffectTheModelLacks) {
  const auto sim = testing::SimulateOrDie(testing::NavigationGradeUnit(), testing::ShortTurnsProfile(300.0, 900.0),
                                          kFindRate10Hz, 32);
  AnalysisRequest request;
  request.nominal = NominalModel();
  request.baseline_effects = {"gyro_bias_rw.x", "acc_scale_factor.y"};
  auto a = Analyze(sim.run, request, AnalysisOptions{});
  ASSERT_TRUE(a.ok()) << a.status();
  std::multiset<std::string> listed;
  for (const EffectCandidate& c : a->report.effect_candidates) listed.insert(c.name);
  for (const EffectTerm& term : AllCatalogueTerms()) {
    const bool in_model = a->model.FindEffect(term) >= 0;
    EXPECT_EQ(listed.count(term.Name()), in_model ? 0u : 1u) << term.Name();
  }
  EXPECT_EQ(listed.count("gyro_bias_rw.x"), 0u);
  for (const EffectCandidate& c : a->report.effect_candidates) {
    if (FindEffectFamily(c.family)->kind != EffectKind::kRandom) continue;
    EXPECT_TRUE(c.source == "LIKELIHOOD" || c.source == "STRUCTURE") << c.name;
    EXPECT_FALSE(c.note.empty()) << c.name << ": says nothing of its test";
    if (!c.tested) {
      EXPECT_TRUE(c.note.starts_with("not tested on this model: ")) << c.name << ": " << c.note;
      EXPECT_EQ(c.p_value_holm, 1.0) << c.name;
    }
    EXPECT_GE(c.p_value_holm, c.p_value) << c.name;
  }
}

// While a constant term is significant the second-order pairs wait for the
// model with it: listed as not tested, with the reason, and left out of
// Holm's correction, which counts exactly the candidates tested.
TEST(Ranking, PairsWaitForTheSignificantConstantTermAndHolmCountsOnlyTheTested) {
  auto unit = testing::NavigationGradeUnit();
  // Twenty tolerances: the short run must show it beyond doubt.
  const FamilyCase c{"GyroScaleFactor", "gyro_scale_factor.z", "rotations", Size::kTolerances, 20.0};
  unit.effects.push_back(HiddenEffect(c, unit));
  const auto sim = testing::SimulateOrDie(unit, testing::ShortTurnsProfile(300.0, 900.0), kFindRate10Hz, 33);
  AnalysisRequest request;
  request.nominal = NominalModel();
  auto a = Analyze(sim.run, request, AnalysisOptions{});
  ASSERT_TRUE(a.ok()) << a.status();
  const std::vector<EffectCandidate>& ranked = a->report.effect_candidates;
  ASSERT_FALSE(ranked.empty());
  ASSERT_EQ(ranked.front().name, c.term);
  ASSERT_LT(ranked.front().p_value_holm, AnalysisOptions{}.finder.family_wise_alpha);
  int untested_pairs = 0, tested = 0;
  for (const EffectCandidate& e : ranked) {
    if (e.identifiable && e.tested) ++tested;
    if (e.family.ends_with("_bias_second_order") && !e.tested) {
      ++untested_pairs;
      EXPECT_NE(e.note.find("a constant term is significant"), std::string::npos) << e.name << ": " << e.note;
      EXPECT_EQ(e.p_value_holm, 1.0);
    }
  }
  EXPECT_GT(untested_pairs, 0);
  // Holm's first step: the smallest p times the number of hypotheses tested.
  EXPECT_NEAR(ranked.front().p_value_holm, std::min(1.0, tested * ranked.front().p_value),
              1e-9 * ranked.front().p_value_holm + 1e-300);
}

TEST(TwoHiddenEffects, DiscoveredInTwoSteps) {
  const std::string gyro_term = "gyro_scale_factor.z";
  const std::string acc_term = "acc_misalignment.yz";
  // Four tolerances each: clearly out of spec, as a unit sent for diagnosis is.
  constexpr double kTolerances = 4.0;
  auto unit = testing::NavigationGradeUnit();
  for (const std::string& name : {gyro_term, acc_term}) {
    sim::TrueEffect e;
    e.term = TermOrDie(name);
    e.value[0] = kTolerances * Tolerance(name);
    unit.effects.push_back(e);
  }
  const auto sim = testing::SimulateOrDie(unit, testing::BuiltinProfileOrDie("full"), kFindRate10Hz, 11);
  AnalysisOptions options;
  AnalysisRequest request;
  request.nominal = NominalModel();
  request.discover = true;
  auto a = Analyze(sim.run, request, options);
  ASSERT_TRUE(a.ok()) << a.status();
  const AnalysisReport& r = a->report;
  for (const DiscoveryStep& d : r.discovery) {
    std::printf("DISCOVERY|%d|%s|%.4g ± %.2g|%.3f|%.1f\n", d.step, d.effect.c_str(), d.estimate, d.std_error, d.fit.nis_mean,
                d.fit.aic);
  }
  if (r.comparison.has_value()) {
    std::printf("DISCOVERY|total|NIS %.3f → %.3f|AIC %.1f → %.1f\n", r.comparison->before.nis_mean,
                r.comparison->after.nis_mean, r.comparison->before.aic, r.comparison->after.aic);
  }
  ASSERT_EQ(r.discovery.size(), 2u);
  const bool gyro_then_acc = Names(r.discovery[0].effect, gyro_term) && Names(r.discovery[1].effect, acc_term);
  const bool acc_then_gyro = Names(r.discovery[0].effect, acc_term) && Names(r.discovery[1].effect, gyro_term);
  EXPECT_TRUE(gyro_then_acc || acc_then_gyro) << r.discovery[0].effect << ", " << r.discovery[1].effect;
  // Each step states one estimate with its error — for a family step, its
  // most significant term's, which is the hidden one — within 3 SE of the truth.
  for (const DiscoveryStep& d : r.discovery) {
    ASSERT_TRUE(std::isfinite(d.estimate) && std::isfinite(d.std_error) && d.std_error > 0.0)
        << d.effect << ": " << d.estimate << " ± " << d.std_error;
    const std::string& hidden = Names(d.effect, gyro_term) ? gyro_term : acc_term;
    const double truth = kTolerances * Tolerance(hidden);
    EXPECT_LE(std::abs(d.estimate - truth), 3.0 * d.std_error)
        << d.effect << ": " << d.estimate << " ± " << d.std_error << ", truth " << truth << " (" << hidden << ")";
  }
  const auto remaining = Significant(r, options.finder.family_wise_alpha);
  EXPECT_TRUE(remaining.empty()) << remaining.front();
  EXPECT_GE(r.fit.nis_mean, r.nis_band_low);
  EXPECT_LE(r.fit.nis_mean, r.nis_band_high);
}

}  // namespace
}  // namespace insdiag::engine
