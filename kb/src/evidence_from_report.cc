// The evidence of one analysis report against a unit type's nominal values
// (kb/include/insdiag/kb/diagnosis.h, "Evidence"; docs/DIAGNOSIS.md): each
// identified parameter and identifiable effect candidate on its scale, a
// drift's σ and τ paired where the report identified them together, and
// each drift's test against nominal.
#include <absl/strings/match.h>
#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>
#include <absl/strings/str_join.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <set>

#include "densities.h"
#include "evidence_text.h"
#include "insdiag/engine/candidate_source.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/model/parameter_key.h"
#include "insdiag/engine/stats/distributions.h"
#include "insdiag/kb/diagnosis.h"
#include "joint_evidence.h"

namespace insdiag::kb {

using internal::Format;
using internal::SignedFormat;

namespace {

// Whether catalogue term `name` (family.axis) is of `kind`: a fault effect
// (bias step or ramp, nominally absent in every unit type) or a random
// structure (a walk or a second-order pair, whose size is a variance).
bool IsEffectOfKind(const std::string& name, engine::EffectKind kind) {
  const std::optional<engine::ParameterKey> key = engine::ParseParameterKey(name);
  return key && key->effect_family != nullptr && key->effect_family->kind == kind;
}

// The z of a two-sided p-value, the standard score a healthy unit scatters as N(0, 1).
double StandardScoreOfPValue(double p_value) {
  return -engine::stats::NormalQuantile(0.5 * std::clamp(p_value, 1e-300, 1.0));
}

// An evidence term on the standard-score scale: a healthy unit scatters as N(0, 1).
EvidenceTerm StandardScoreTerm(const std::string& name, double estimate, double std_error, const std::string& unit,
                               double z, bool significant, const std::string& suffix,
                               const DiagnosisSettings& settings) {
  EvidenceTerm t;
  t.name = name;
  t.scale = Scale::kZ;
  t.x = z;
  t.measurement_sd = 0.0;
  t.healthy_sd = settings.healthy_z_sd;
  t.significant = significant;
  t.tolerance_units = 0.0;
  t.line = absl::StrCat(name, ": estimate ", Format(estimate), std_error > 0 ? absl::StrCat(" ± ", Format(std_error)) : "",
                        unit.empty() ? "" : " ", unit, " (", absl::StrFormat("%.1f", z), " standard errors)", suffix);
  return t;
}

}  // namespace

namespace {

// A value against its nominal, on the scale the nominal calls for.
EvidenceTerm AgainstNominal(const std::string& name, double value, double std_error,
                            const NominalParameter& n, const std::string& unit,
                            const DiagnosisSettings& settings) {
  EvidenceTerm t;
  t.name = name;
  t.tolerance_units = (value - n.value) / n.tolerance;
  const double se = std::isfinite(std_error) && std_error > 0 ? std_error : 0.0;
  const std::string u = unit.empty() ? n.unit : unit;
  const std::string se_text = se > 0 ? absl::StrCat(" ± ", Format(se)) : "";
  if (n.value > 0 && value > 0) {
    t.scale = Scale::kLogRatio;
    t.x = std::log(value / n.value);
    t.measurement_sd = se / value;
    t.healthy_sd = settings.healthy_log_ratio_fraction * std::log1p(n.tolerance / n.value);
    t.line =
        absl::StrCat(name, " = ", Format(value), se_text, " ", u, ", ",
                     absl::StrFormat("%.2g", value / n.value), "× nominal ", Format(n.value),
                     " (", SignedFormat(t.tolerance_units), " tolerance units)");
  } else {
    t.scale = Scale::kTolerance;
    t.x = t.tolerance_units;
    t.measurement_sd = se / n.tolerance;
    t.healthy_sd = settings.healthy_tolerance_sd;
    t.line = absl::StrCat(name, " = ", SignedFormat(value), se_text, (u.empty() ? "" : " "), u,
                          " (", SignedFormat(t.tolerance_units), " tolerance units, tolerance ",
                          Format(n.tolerance), ")");
  }
  return t;
}

// A candidate's standard score as evidence.
// A random structure (a walk, a second-order pair): its magnitude is
// bounded at zero, so estimate over SE is positive whatever the unit and
// no standard score (a pair its own test does not support can stand several
// SE from zero); the z of its likelihood-ratio test's p-value is.
// Without a standard error, the z of the same two-sided p-value: √χ² on
// one degree of freedom, and on more not an inflated √χ² (a pair's 2Δℓ
// has three). A fault from the onset scan: its estimate over its SE is
// the best onset's, inflated by the search over onsets; the z of its
// p-value (Davies' bound over the onsets) is what a healthy unit
// scatters like N(0, 1); so is that of a ramp the raw samples show (its
// test picked the channel and the onset).
double CandidateStandardScore(const CandidateFinding& c) {
  const auto z_of_p = [&] {
    return std::copysign(StandardScoreOfPValue(c.p_value), c.estimate);
  };
  const std::optional<engine::CandidateSource> source = engine::CandidateSourceNamed(c.source);
  const bool structure = source && engine::IsStructureSource(*source);
  const bool fault = source && engine::IsFaultTestSource(*source);
  return fault || structure  ? z_of_p()
         : c.std_error > 0 ? c.estimate / c.std_error
         : c.degrees_of_freedom <= 1
             ? std::copysign(std::sqrt(std::max(c.statistic, 0.0)), c.estimate)
             : z_of_p();
}

// A random structure the loop added (a walk, a second-order pair) is in the
// model, so no candidate scores it and the model lists only its density; the
// test that added it does score it, as it scored the candidate before
// (z of its Holm-adjusted p-value: a conservative score).
void AddStructuresTheLoopAdded(const ReportFindings& report,
                               const DiagnosisSettings& settings, std::set<std::string>& seen,
                               Evidence& evidence) {
  const std::vector<std::string>& effects = report.model_effects;
  for (const LoopStep& step : report.discovery) {
    const std::string& name = step.effect;
    const bool in_model = std::find(effects.begin(), effects.end(), name) != effects.end();
    if (!IsEffectOfKind(name, engine::EffectKind::kRandom) || !in_model ||
        !seen.insert(name).second)
      continue;
    evidence.terms.push_back(StandardScoreTerm(
        name, step.estimate, step.std_error, step.unit, StandardScoreOfPValue(step.p_value),
        true,
        absl::StrFormat(", in the model (added by the loop at step %d, Holm p = %.2g)", step.step,
                        step.p_value),
        settings));
  }
}

// Pairs a drift's σ and τ where the report identified them together and
// both stand against a nominal on the log-ratio scale; a term whose partner
// is missing is weighed alone.
void PairJointlyIdentified(const ReportFindings& report, Evidence& evidence) {
  const std::map<std::string, std::size_t> index = internal::TermsByName(evidence);
  for (const IdentifiedFinding& p : report.identified) {
    if (!p.log_correlation || !(std::abs(*p.log_correlation) < 1.0)) continue;
    const auto a = index.find(p.name);
    const auto b = index.find(p.jointly_with);
    if (a == index.end() || b == index.end() || a->second == b->second) continue;
    EvidenceTerm& first = evidence.terms[a->second];
    EvidenceTerm& second = evidence.terms[b->second];
    if (first.scale != Scale::kLogRatio || second.scale != Scale::kLogRatio) continue;
    first.jointly_with = second.name;
    second.jointly_with = first.name;
    first.measurement_correlation = second.measurement_correlation = *p.log_correlation;
  }
}

bool IsDriftSigma(const std::string& name) {
  const std::optional<engine::ParameterKey> key = engine::ParseParameterKey(name);
  return key && absl::EndsWith(key->family, "_bias_gm") && key->field == engine::ParameterField::kSigma;
}

// Each drift's distance from nominal as one test: d² = xᵀ(diag(s_h²) + M)⁻¹x,
// χ² on two degrees of freedom for σ and τ together, on one for σ alone,
// Holm-adjusted over the unit's drifts (Holm, Scand. J. Statist. 6(2),
// 1979). A drift that wandered along the ridge is as far as its
// well-measured direction says, not as its two wide marginals do.
void TestDrifts(const DiagnosisSettings& settings, Evidence& evidence) {
  struct DriftTest {
    std::size_t sigma = 0;
    std::optional<std::size_t> tau;
    double statistic = 0.0;
    int dof = 1;
  };
  const std::vector<std::optional<std::size_t>> partners = internal::PartnersOf(evidence);
  std::vector<DriftTest> tests;
  std::vector<double> p_values;
  for (std::size_t i = 0; i < evidence.terms.size(); ++i) {
    const EvidenceTerm& t = evidence.terms[i];
    if (!IsDriftSigma(t.name) || t.scale != Scale::kLogRatio || !t.trend_of.empty()) continue;
    DriftTest test;
    test.sigma = i;
    test.tau = partners[i];
    if (test.tau) {
      test.statistic = internal::PairDistanceSquared(t, evidence.terms[*test.tau], t.measurement_correlation);
      test.dof = 2;
    } else {
      test.statistic = t.x * t.x / internal::HealthyVariance(t);
    }
    tests.push_back(test);
    p_values.push_back(engine::stats::ChiSquareSurvival(test.statistic, test.dof));
  }
  std::vector<double> holm(p_values.size());
  engine::stats::HolmAdjust(p_values, holm);
  for (std::size_t k = 0; k < tests.size(); ++k) {
    const DriftTest& test = tests[k];
    const bool significant = holm[k] < settings.significance_level;
    EvidenceTerm& sigma = evidence.terms[test.sigma];
    sigma.significant = significant;
    absl::StrAppend(&sigma.line,
                    absl::StrFormat("; the drift %s: χ²%s = %.3g from nominal, Holm p = %.2g over %d drifts%s",
                                    test.tau ? "with its τ" : "alone", test.dof == 2 ? "₂" : "₁",
                                    test.statistic, holm[k], static_cast<int>(tests.size()),
                                    significant ? ", significant" : ""));
    if (test.tau) evidence.terms[*test.tau].significant = significant;
  }
}

}  // namespace

Evidence EvidenceFromReport(const ReportFindings& report, const UnitType& unit_type,
                            const DiagnosisSettings& settings) {
  Evidence evidence;
  evidence.verdict = report.verdict;
  std::map<std::string, const NominalParameter*> nominal;
  for (const NominalParameter& p : unit_type.nominal) nominal[p.name] = &p;
  std::set<std::string> seen;
  std::vector<std::string> unknown_names;

  for (const IdentifiedFinding& p : report.identified) {
    const auto it = nominal.find(p.name);
    if (it == nominal.end() && IsEffectOfKind(p.name, engine::EffectKind::kFault) &&
        p.std_error > 0 && seen.insert(p.name).second) {
      // A fault the model holds (added at its onset): nominally absent, its
      // estimate in standard errors.
      evidence.terms.push_back(StandardScoreTerm(p.name, p.value, p.std_error, p.unit,
                                                 p.value / p.std_error, true, ", in the model", settings));
      continue;
    }
    if (it == nominal.end()) {
      unknown_names.push_back(p.name);
      continue;
    }
    if (!seen.insert(p.name).second) continue;
    EvidenceTerm t =
        AgainstNominal(p.name, p.value, p.std_error, *it->second, p.unit, settings);
    absl::StrAppend(&t.line, ", identified (", p.method, ")");
    evidence.terms.push_back(std::move(t));
  }
  PairJointlyIdentified(report, evidence);
  TestDrifts(settings, evidence);
  AddStructuresTheLoopAdded(report, settings, seen, evidence);
  int significant_candidates = 0;
  for (const CandidateFinding& c : report.candidates) {
    // A candidate no test measured is no evidence either way.
    if (!c.identifiable || c.not_tested || !seen.insert(c.name).second) continue;
    const bool significant = c.p_value_holm < settings.significance_level;
    significant_candidates += significant ? 1 : 0;
    const std::string verdict =
        significant ? absl::StrFormat(", significant (Holm p = %.2g)", c.p_value_holm)
                    : absl::StrFormat(", not significant (Holm p = %.2g)", c.p_value_holm);
    const auto it = nominal.find(c.name);
    if (it != nominal.end()) {
      EvidenceTerm t =
          AgainstNominal(c.name, c.estimate, c.std_error, *it->second, c.unit, settings);
      t.significant = significant;
      absl::StrAppend(&t.line, verdict);
      evidence.terms.push_back(std::move(t));
      continue;
    }
    const double z = CandidateStandardScore(c);
    std::string where;
    if (c.onset_s) where = absl::StrFormat(" from %.0f ± %.0f s", *c.onset_s, c.onset_std_s);
    evidence.terms.push_back(StandardScoreTerm(c.name, c.estimate, c.std_error, c.unit, z, significant,
                                               where + verdict, settings));
  }
  // Candidates scanned against one model are each tested beside that model
  // alone: one fault's knock-on effects (a gyro jump tilts the unit, and the
  // other gyros' and the accelerometers' terms score) read as evidence of
  // their own, which only `unknown` explains. The loop's end has them in
  // or out of its model.
  if (significant_candidates > 1) {
    evidence.notes.push_back(absl::StrFormat(
        "the analysed model leaves %d significant missing effects, each tested against that model "
        "alone: the knock-on effects of one fault count as evidence of others; diagnose the "
        "analysis "
        "that walks the loop (discover) to read them with the first effect in the model",
        significant_candidates));
  }
  // A unit whose noise the analysis found of another class than its type:
  // every term reads far from nominal for that reason alone.
  if (report.unit_type_set_aside.has_value()) {
    const UnitTypeSetAside& aside = *report.unit_type_set_aside;
    evidence.notes.push_back(absl::StrFormat(
        "the analysis set %s's nominal model aside: the run's Allan deviation on %s at τ %.3g s is %.3g times "
        "it, so the unit's noise is of another class, and every term below reads far from nominal for that "
        "reason; check the unit's type before reading the modes",
        unit_type.name, aside.channel, aside.tau_s, aside.ratio));
  }
  if (!unknown_names.empty()) {
    evidence.notes.push_back(absl::StrCat("identified parameters without a nominal value in ", unit_type.name,
                                          " are not used: ", absl::StrJoin(unknown_names, ", ")));
  }
  if (evidence.terms.empty()) {
    evidence.notes.push_back(
        "the report carries no identified parameters or identifiable effect candidates: the diagnosis rests on "
        "its verdict alone");
  }
  return evidence;
}

}  // namespace insdiag::kb
