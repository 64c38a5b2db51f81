#include "analysis/missing_effects.h"

#include <absl/strings/str_format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <optional>

#include "analysis/fault_passes.h"
#include "analysis/steps_in_raw_samples.h"
#include "insdiag/engine/finder/effect_finder.h"
#include "insdiag/engine/finder/fault_findings.h"
#include "insdiag/engine/finder/warm_up_scan.h"
#include "insdiag/engine/model/parameter_field.h"
#include "insdiag/engine/numerics/parallel_map.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine::pipeline {

// The drifts correlation processing resolved.
DriftSelection ResolvedDrifts(const std::vector<DriftCorrelation>& drifts) {
  DriftSelection selection;
  for (const DriftCorrelation& c : drifts) {
    if (c.analysis.resolved) selection.Set(DriftAxis{c.sensor, c.axis});
  }
  return selection;
}

namespace {

// What a scan's structure tests said of the random structures they did not
// propose, by effect name: each one's statistic below its screen, or why it
// was not tested. The report lists every catalogue effect the model lacks.
using StructureOutcomes = std::map<std::string, EffectCandidate>;

// A random structure's candidate from `source` ("STRUCTURE", "LIKELIHOOD")
// with nothing measured yet: no statistic, no estimate (p = 1); its degrees
// of freedom are the structure's own parameters.
EffectCandidate StructureCandidate(const EffectTerm& term, const char* source) {
  EffectCandidate c;
  c.name = term.Name();
  c.family = std::string(term.family->name);
  c.unit = std::string(term.family->unit);
  c.source = source;
  c.dof = term.family->process == RandomProcess::kSecondOrderMarkov ? 3 : 1;
  c.std_error = std::numeric_limits<double>::infinity();
  return c;
}

// The catalogue effect a correlation-function family of drift `d` means, with
// its magnitude: a walk (random walk; a second exponential longer than half
// the run, dσ²/dt = 2σ₂²/τ₂), a second-order pair (exponential-cosine).
std::optional<StructureProposal> StructureOfFit(const DriftCorrelation& d, const ident::FamilyFit& f, double run_s) {
  const DriftAxis drift{d.sensor, d.axis};
  StructureProposal p;
  std::string effect;
  if (f.family == ident::CorrelationFamily::kRandomWalk) {
    effect = WalkName(drift);
    p.effect.random_walk_density = f.Parameter(ident::CorrelationParameter::kDensity)->value;
    p.candidate.estimate = p.effect.random_walk_density;
    p.candidate.std_error = f.Parameter(ident::CorrelationParameter::kDensity)->std_error;
  } else if (f.family == ident::CorrelationFamily::kExponentialCosine) {
    effect = SecondOrderName(drift);
    p.effect.second_order_sigma = f.Parameter(ident::CorrelationParameter::kSigma2)->value;
    p.effect.second_order_alpha_per_s =
        1.0 / f.Parameter(ident::CorrelationParameter::kTau2)->value;
    p.effect.second_order_beta_rad_s =
        2.0 * std::numbers::pi / f.Parameter(ident::CorrelationParameter::kPeriod)->value;
    p.candidate.estimate = p.effect.second_order_sigma;
    p.candidate.std_error = f.Parameter(ident::CorrelationParameter::kSigma2)->std_error;
    p.searched_starts = 16;  // the profile grid of period × decay (correlation.cc)
  } else if (f.family == ident::CorrelationFamily::kTwoExponentials &&
             f.Parameter(ident::CorrelationParameter::kTau2)->value >= 0.5 * run_s) {
    effect = WalkName(drift);
    const double s2 = f.Parameter(ident::CorrelationParameter::kSigma2)->value;
    const double t2 = f.Parameter(ident::CorrelationParameter::kTau2)->value;
    p.effect.random_walk_density = s2 * std::sqrt(2.0 / t2);
    p.candidate.estimate = p.effect.random_walk_density;
    p.candidate.std_error =
        f.Parameter(ident::CorrelationParameter::kSigma2)->std_error * std::sqrt(2.0 / t2);
    p.searched_starts = 6;
  } else {
    return std::nullopt;
  }
  auto terms = ParseEffectSelector(effect);
  if (!terms.ok()) return std::nullopt;
  p.effect.term = terms->front();
  EffectCandidate c = StructureCandidate(p.effect.term, "STRUCTURE");
  c.estimate = p.candidate.estimate;
  c.std_error = p.candidate.std_error;
  c.note = std::string("correlation function of ") + d.state + " is " + ident::CorrelationFamilyName(f.family) +
           ", not exponential";
  p.candidate = std::move(c);
  return p;
}

// Correlation processing's structures on the drifts it resolved: those whose
// family beats the exponential at `screen_alpha` are proposed; the others'
// tests go to `outcomes` (the stronger where two families mean one effect).
std::vector<StructureProposal> ProposeStructures(const std::vector<DriftCorrelation>& drifts, double run_s,
                                                 double screen_alpha, StructureOutcomes& outcomes) {
  std::vector<StructureProposal> out;
  for (const DriftCorrelation& d : drifts) {
    if (!d.analysis.resolved) continue;
    for (const ident::FamilyFit& f : d.analysis.fits) {
      if (!f.usable) continue;
      std::optional<StructureProposal> p = StructureOfFit(d, f, run_s);
      if (!p.has_value()) continue;
      if (f.lr_p_value >= screen_alpha) {
        EffectCandidate c = p->candidate;
        c.statistic = f.lr_statistic;
        c.dof = f.lr_dof;
        c.p_value = f.lr_p_value;
        c.note = "correlation function of " + d.state + " against " + ident::CorrelationFamilyName(f.family) +
                 absl::StrFormat("; its fit to the correlation function gains χ² %.1f, p = %.2g (%d starts): "
                                 "below the screen",
                                 f.lr_statistic, f.lr_p_value, p->searched_starts);
        auto [it, inserted] = outcomes.emplace(c.name, c);
        if (!inserted && c.p_value < it->second.p_value) it->second = c;
        continue;
      }
      // The first family that means an effect proposes it.
      if (std::none_of(out.begin(), out.end(),
                       [&](const StructureProposal& o) { return o.effect.term == p->effect.term; })) {
        out.push_back(*std::move(p));
      }
    }
  }
  return out;
}

// Confirms each proposal with the filter's exact likelihood: model A plus the
// effect, against model A.
std::vector<StructureProposal> ConfirmStructures(const EpochRun& epochs, const ModelPass& a,
                                                 std::vector<StructureProposal> proposals) {
  const double log_n = std::log(static_cast<double>(std::max(1, a.forward.scalar_updates)));
  const auto needs_pass = [&](const StructureProposal& p) {
    return !p.fitted.has_value() && a.model.FindEffect(p.effect.term) < 0;
  };
  // Each proposal's pass is independent of the others'.
  std::vector<absl::StatusOr<double>> log_likelihoods =
      numerics::ParallelMap(proposals.size(), [&](std::size_t i) -> absl::StatusOr<double> {
        if (!needs_pass(proposals[i])) return 0.0;
        ErrorModel b = a.model;
        b.effects.push_back(proposals[i].effect);
        return ProfileLogLikelihood(epochs, b);
      });
  for (std::size_t i = 0; i < proposals.size(); ++i) {
    StructureProposal& p = proposals[i];
    if (!needs_pass(p)) continue;
    const absl::StatusOr<double>& pass = log_likelihoods[i];
    EffectCandidate& c = p.candidate;
    if (!pass.ok()) {
      c.identifiable = false;
      c.note += "; could not confirm: " + std::string(pass.status().message());
      continue;
    }
    c.statistic = std::max(0.0, 2.0 * (*pass - a.log_likelihood));
    c.p_value = ident::StructurePValue(c.statistic, c.dof, p.searched_starts);
    c.predicted_delta_aic = -c.statistic + 2.0 * c.dof;
    c.predicted_delta_bic = -c.statistic + c.dof * log_n;
  }
  return proposals;
}

constexpr std::string_view kMeasuredOn = "measured on ";

// The outcome `settled` holds for structure `name`, if the likelihood's test
// found nothing there: shrunk by the screen, or below `screen_alpha`.
const EffectCandidate* SettledOutcome(const SettledStructures& settled, const std::string& name, double screen_alpha) {
  for (const EffectCandidate& c : settled.candidates) {
    if (c.name == name && c.source == "LIKELIHOOD" && c.tested && c.identifiable && !(c.p_value < screen_alpha)) {
      return &c;
    }
  }
  return nullptr;
}

// A random structure no test measured on this model, and why.
EffectCandidate UntestedStructure(const EffectTerm& term, const std::string& why) {
  EffectCandidate c = StructureCandidate(term, "LIKELIHOOD");
  c.tested = false;
  c.note = "not tested on this model: " + why;
  return c;
}

// What one likelihood test of structures said: the structures it keeps,
// as proposals; into `outcomes`, those its screen shrank and those below the
// screen.
void ReadStructureTest(const ident::DriftLikelihoodResult& fitted,
                       std::string (*structure_name)(DriftAxis), const ModelPass& pass,
                       double screen_alpha, double log_n, StructureOutcomes& outcomes,
                       std::vector<StructureProposal>& out) {
  // The axes the screen tried: a structure its first EM step shrank (not
  // among `structures`) is one this run does not tell from the axis' drift.
  for (const DriftAxis d : DriftAxis::All()) {
    const std::string name = structure_name(d);
    auto terms = ParseEffectSelector(name);
    if (!fitted.screened.Contains(d) || !terms.ok()) continue;
    EffectCandidate c = StructureCandidate(terms->front(), "LIKELIHOOD");
    c.note = std::string(
                 "likelihood of the innovations: the first EM step from the structure hypothesis "
                 "shrank it — this run does not tell it from a wider ") +
             DriftName(d) + " drift";
    outcomes.insert_or_assign(name, c);
  }
  for (const ident::StructureEstimate& w : fitted.structures) {
    auto terms = ParseEffectSelector(w.effect);
    if (!terms.ok()) continue;
    if (w.refused_by_raw_samples.has_value()) {
      outcomes.insert_or_assign(
          w.effect,
          UntestedStructure(
              terms->front(),
              absl::StrFormat("likelihood of the innovations: 2Δℓ = %.1f beyond the drift σ "
                              "re-fitted alone, but its Allan variance with the drift at a "
                              "cluster time of %.3g s is %.3g times what the static "
                              "segments' raw samples allow: not this unit's",
                              w.statistic, w.refused_by_raw_samples->cluster_time_s,
                              w.refused_by_raw_samples->ratio)));
      continue;
    }
    if (!(ident::NestedPValue(w) < screen_alpha)) {
      EffectCandidate c = StructureCandidate(terms->front(), "LIKELIHOOD");
      c.estimate = w.parameters.front().value;
      c.statistic = w.statistic;
      c.p_value = ident::NestedPValue(w);
      c.note = absl::StrFormat(
          "likelihood of the innovations: 2Δℓ = %.1f beyond the drift σ re-fitted "
          "alone, p = %.2g (%d starts) — below the screen; no standard error computed",
          w.statistic, c.p_value, w.starts);
      outcomes.insert_or_assign(w.effect, c);
      continue;
    }
    StructureProposal p;
    p.effect = w.fitted;
    p.fitted = w;
    p.candidate = StructureCandidate(p.effect.term, "LIKELIHOOD");
    EffectCandidate& c = p.candidate;
    c.estimate = w.parameters.front().value;
    c.std_error = w.parameters.front().std_error;
    c.dof = w.dof + 1;
    // With several structures kept, the joint gain less the others' own.
    double others = 0.0;
    for (const ident::StructureEstimate& o : fitted.structures)
      others += o.drift == w.drift ? 0.0 : o.statistic;
    c.statistic =
        std::max(w.statistic, 2.0 * (fitted.log_likelihood_after - pass.log_likelihood) - others);
    // χ² for a parameter on its boundary is conservative (drift_likelihood.h).
    c.p_value = ident::StructurePValue(c.statistic, c.dof, w.starts);
    c.predicted_delta_aic = -c.statistic + 2.0 * c.dof;
    c.predicted_delta_bic = -c.statistic + c.dof * log_n;
    std::string parameters;
    for (const ParameterEstimate& e : w.parameters) {
      parameters += absl::StrFormat("%s%s %.3g %s", parameters.empty() ? "" : ", ",
                                    FieldSuffix(SplitParameterName(e.name).field), e.value, e.unit);
    }
    c.note = "likelihood of the innovations with " + parameters + " and the drift σ re-fitted (" +
             DriftName(w.drift) + ".sigma " +
             absl::StrFormat("%.3g %s", w.drift_sigma.value, w.drift_sigma.unit) + " with it); " +
             absl::StrFormat("2Δℓ = %.1f beyond the drift σ re-fitted alone", w.statistic);
    out.push_back(std::move(p));
  }
}

// Bias random walks and second-order pairs by the innovations' likelihood
// (drift_likelihood.h), on every drift axis the model has none on. Also on a
// run whose monitoring flags faults: a walk that has wandered far trips the
// drift monitor, and the candidate hides nothing — the report keeps the
// fault intervals of its model. As correlation processing's structures, a
// structure is screened, then measured against model A: the screen is the
// nested test (the structure beyond its drift σ re-fitted alone, χ² with its
// own parameters, at `screen_alpha` over the fit's starting points) — a
// wider drift alone is not a structure; the statistic is 2(ℓ̂ − ℓ_A), what
// the structure with its re-fitted drift explains of model A's innovations,
// on its parameters and the drift σ, the scale every other candidate is
// ranked on.
//
// Walks on every axis. Second-order pairs on the axes whose drift
// correlation processing left unresolved — where it resolves the drift, its
// exponential-cosine family tests the pair (ProposeStructures) — and only
// while no constant term is significant: a pair fitted to a model that lacks
// a constant effect soaks up that effect's signal (a drift widened to carry
// a scale factor, in another guise), and each of its passes costs more than
// a base pass (two states an axis). The constant effect is added first; the
// next scan tests the pairs.
std::vector<StructureProposal> LikelihoodStructureProposals(const EpochRun& epochs, const ModelPass& pass,
                                                            const ErrorModel& a_priori,
                                                            const std::vector<DriftCorrelation>& drifts,
                                                            bool constant_significant, double screen_alpha,
                                                            const ident::DriftCeilings& ceilings,
                                                            const AnalysisOptions& options,
                                                            const SettledStructures& settled,
                                                            StructureOutcomes& outcomes,
                                                            DecisionLog* decisions) {
  std::vector<StructureProposal> out;
  const DriftSelection every_axis = DriftSelection::Every();
  DriftSelection unresolved;
  const DriftSelection resolved = ResolvedDrifts(drifts);
  for (const DriftAxis d : DriftAxis::All()) unresolved.Set(d, !resolved.Contains(d));
  const double log_n = std::log(static_cast<double>(std::max(1, pass.forward.scalar_updates)));
  struct Test {
    bool enabled;
    const char* what;
    decltype(&ident::IdentifyWalksByLikelihood) fit;
    DriftSelection axes;
    decltype(&WalkName) structure_name;
  };
  const Test tests[] = {
      {options.test_walks_by_likelihood, "bias random walks", &ident::IdentifyWalksByLikelihood, every_axis,
       &WalkName},
      {options.test_second_orders_by_likelihood && !constant_significant, "second-order drifts",
       &ident::IdentifySecondOrdersByLikelihood, unresolved, &SecondOrderName},
  };
  if (options.test_second_orders_by_likelihood && constant_significant) {
    for (const DriftAxis d : DriftAxis::All()) {
      if (!unresolved.Contains(d)) continue;
      auto terms = ParseEffectSelector(SecondOrderName(d));
      if (!terms.ok()) continue;
      outcomes.insert_or_assign(
          terms->front().Name(),
          UntestedStructure(terms->front(), "a constant term is significant, and a pair fitted beside a missing "
                                            "constant effect soaks up its signal: the model with that effect "
                                            "tests it"));
    }
  }
  // The axes each test fits: those no earlier model settled.
  constexpr std::size_t kTests = std::size(tests);
  std::array<DriftSelection, kTests> axes_of;
  for (std::size_t t = 0; t < kTests; ++t) {
    const Test& test = tests[t];
    if (!test.enabled) continue;
    DriftSelection& axes = axes_of[t];
    axes = test.axes;
    for (const DriftAxis d : DriftAxis::All()) {
      const EffectCandidate* was = SettledOutcome(settled, test.structure_name(d), screen_alpha);
      if (was == nullptr || !axes.Contains(d)) continue;
      axes.Set(d, false);
      EffectCandidate c = *was;
      // An outcome carried further keeps the first model it was measured on.
      if (!settled.measured_on.empty() && !c.note.starts_with(kMeasuredOn)) {
        c.note = std::string(kMeasuredOn) + settled.measured_on + ": " + c.note;
      }
      outcomes.insert_or_assign(c.name, c);
    }
  }
  // The two tests alongside each other: each is mostly one EM chain, a pass
  // after the other, which holds one core; their results are read in order
  // below, as if they had run one after the other.
  static_assert(kTests == 2, "the walks (0) and the second-order pairs (1)");
  std::array<std::optional<absl::StatusOr<ident::DriftLikelihoodResult>>, kTests> fits;
  auto fit = [&](std::size_t t) {
    if (tests[t].enabled && axes_of[t].Any()) {
      fits[t] = tests[t].fit(epochs, pass.model, a_priori, axes_of[t], screen_alpha, ceilings,
                             options.drift_likelihood);
    }
  };
  numerics::AlongsideEachOther([&] { fit(1); }, [&] { fit(0); });
  for (std::size_t t = 0; t < kTests; ++t) {
    const Test& test = tests[t];
    if (!fits[t].has_value()) continue;
    const absl::StatusOr<ident::DriftLikelihoodResult>& fitted = *fits[t];
    if (!fitted.ok()) {
      if (decisions != nullptr) {
        decisions->Note(std::string("no likelihood test of ") + test.what + ": " +
                         std::string(fitted.status().message()));
      }
      continue;
    }
    ReadStructureTest(*fitted, test.structure_name, pass, screen_alpha, log_n, outcomes, out);
  }
  return out;
}

// Terms and structures ranked together, Holm over all that were tested:
// the structures proposed, and the others with what their tests said. The
// candidates significant at family-wise `alpha` come first, the most probable
// explanation first: lowest predicted ΔBIC, the order in which the analysis
// adds them (Schwarz, Ann. Stat. 6(2), 1978). Beyond significance a p-value
// no longer ranks explanations: a step and a ramp on one axis carry the same
// evidence, but the bound on the maximum over onsets penalises them unequally.
// The rest follow by Holm-adjusted p-value. Of look-alike faults the run
// cannot tell apart, the one its sensor's raw samples show comes first, else
// the smaller change of the unit (fault_findings.h, IsLikelierLookAlike).
std::vector<EffectCandidate> MergeCandidates(std::vector<EffectCandidate> terms,
                                             const std::vector<StructureProposal>& structures,
                                             std::vector<EffectCandidate> other_structures, double alpha) {
  for (const StructureProposal& s : structures) terms.push_back(s.candidate);
  for (EffectCandidate& c : other_structures) terms.push_back(std::move(c));
  std::vector<size_t> tested;
  std::vector<double> p;
  for (size_t i = 0; i < terms.size(); ++i) {
    if (!terms[i].identifiable || !terms[i].tested) continue;
    tested.push_back(i);
    p.push_back(terms[i].p_value);
  }
  std::vector<double> adjusted(p.size());
  stats::HolmAdjust(p, adjusted);
  for (size_t j = 0; j < tested.size(); ++j) terms[tested[j]].p_value_holm = adjusted[j];
  std::stable_sort(terms.begin(), terms.end(), [alpha](const EffectCandidate& a, const EffectCandidate& b) {
    if (a.identifiable != b.identifiable) return a.identifiable;
    if (a.SignificantAt(alpha) != b.SignificantAt(alpha)) return a.SignificantAt(alpha);
    if (a.SignificantAt(alpha) && a.predicted_delta_bic != b.predicted_delta_bic) {
      return a.predicted_delta_bic < b.predicted_delta_bic;
    }
    if (a.p_value_holm != b.p_value_holm) return a.p_value_holm < b.p_value_holm;
    return a.statistic > b.statistic;
  });
  PutLikelierLookAlikesFirst(terms, alpha);
  return terms;
}

// The faults a pass shows: significant fault candidates of its scan that
// stand together, and the fault effects of its model whose estimates differ
// from zero.
std::vector<FaultFinding> FaultFindings(const RunContext& c, const ModelPass& pass,
                                        const Findings& found, DecisionLog& decisions) {
  const AnalysisOptions& options = c.options;
  const double alpha = options.finder.family_wise_alpha;
  std::vector<FaultFinding> findings =
      FaultsThatStandTogether(c, pass, SignificantFaults(found.candidates, alpha), decisions);
  const int K = pass.forward.epochs();
  if (K == 0) return findings;
  for (const SensorState& s : pass.layout->sensor_states()) {
    if (s.effect < 0) continue;
    const ModelEffect& e = pass.model.effects[static_cast<size_t>(s.effect)];
    if (e.term.family->kind != EffectKind::kFault) continue;
    const auto f = FaultInModel(e.term, e.onset_s, pass.forward.x_filt(K - 1, s.index),
                                std::sqrt(pass.smoothed.variance(K - 1, s.index)), alpha);
    if (f.has_value()) findings.push_back(*f);
  }
  return findings;
}

}  // namespace

// `drifts`: correlation processing of this pass's smoothed drifts.
Findings FindMissingEffects(const RunContext& context, const ModelPass& pass, std::vector<DriftCorrelation> drifts,
                            const AnalysisOptions& options, DecisionLog* decisions,
                            const SettledStructures& settled) {
  const BenchRun& run = context.run;
  const EpochRun& epochs = context.epochs;
  const ErrorModel& a_priori = context.a_priori.model;
  const RawSampleEvidence& raw_samples = context.raw_samples;
  Findings f;
  f.drifts = std::move(drifts);
  RankedEffects ranked =
      RankMissingEffects(*pass.scan, pass.forward, run, pass.segment_motion, options.finder,
                         RawConstantsComparable(raw_samples, pass.model));
  f.families = std::move(ranked.families);
  // Screening level of a structure before the likelihood confirms it: the
  // family-wise α over the drifts and the structural families tried.
  const double screen_alpha = options.finder.family_wise_alpha / (6.0 * 3.0);
  // The likelihood's structures first: where correlation processing proposes
  // the same structure, the likelihood's estimate is kept.
  const bool constant_significant =
      std::any_of(ranked.terms.begin(), ranked.terms.end(), [&](const EffectCandidate& c) {
        return c.SignificantAt(options.finder.family_wise_alpha);
      });
  StructureOutcomes likelihood_outcomes, correlation_outcomes;
  std::vector<StructureProposal> proposals = LikelihoodStructureProposals(
      epochs, pass, a_priori, f.drifts, constant_significant, screen_alpha, context.drift_ceilings, options, settled,
      likelihood_outcomes, decisions);
  for (StructureProposal& p : ProposeStructures(f.drifts, run.DurationS(), screen_alpha, correlation_outcomes)) {
    if (std::none_of(proposals.begin(), proposals.end(),
                     [&](const StructureProposal& o) { return o.effect.term == p.effect.term; })) {
      proposals.push_back(std::move(p));
    }
  }
  // Structures already in the model are not candidates.
  proposals.erase(std::remove_if(proposals.begin(), proposals.end(),
                                 [&](const StructureProposal& p) { return pass.model.FindEffect(p.effect.term) >= 0; }),
                  proposals.end());
  // Every other random structure of the catalogue the model lacks, with what
  // its test said (the likelihood's where it ran), or why none ran.
  std::vector<EffectCandidate> others;
  for (const EffectTerm& term : AllCatalogueTerms()) {
    if (term.family->kind != EffectKind::kRandom || pass.model.FindEffect(term) >= 0 ||
        std::any_of(proposals.begin(), proposals.end(), [&](const StructureProposal& p) { return p.effect.term == term; })) {
      continue;
    }
    const std::string name = term.Name();
    if (auto it = likelihood_outcomes.find(name); it != likelihood_outcomes.end()) {
      others.push_back(it->second);
    } else if (auto jt = correlation_outcomes.find(name); jt != correlation_outcomes.end()) {
      others.push_back(jt->second);
    } else {
      others.push_back(UntestedStructure(
          term, DriftOf(pass.model, DriftAxis::Of(term)).sigma > 0.0
                    ? "neither the likelihood's test (off, or failed: see the notes) nor correlation processing's "
                      "(the " + DriftName(DriftAxis::Of(term)) + " drift unresolved, or its fit not converged) "
                      "measured it"
                    : "the model has no " + DriftName(DriftAxis::Of(term)) + " drift to test it beside"));
    }
  }
  f.structures = ConfirmStructures(epochs, pass, std::move(proposals));
  FaultScale scale;
  for (int a = 0; a < 3; ++a) {
    for (const Sensor sensor : {Sensor::kGyro, Sensor::kAccelerometer}) {
      const SensorTriadModel& triad = sensor == Sensor::kGyro ? pass.model.gyro : pass.model.acc;
      const auto i = static_cast<size_t>(SensorAxisIndex(sensor, a));
      scale.drift_sigma[i] = triad.bias[static_cast<size_t>(a)].sigma;
      scale.drift_tau_s[i] = triad.bias[static_cast<size_t>(a)].tau_s;
      scale.white_noise_density[i] = triad.white_noise_density[a];
    }
  }
  if (epochs.size() > 0) scale.run_end_s = epochs.epochs.back().time_s;
  std::vector<EffectCandidate> faults =
      FaultCandidates(pass.onsets, pass.forward.scalar_updates, scale, raw_samples.changes);
  ConfirmFaultsOutsideTheLinearRange(run, pass, options, faults);
  WeighStepsByTheirRawSamples(faults, run, raw_samples, options.onset_scan.min_side_s,
                              options.finder.family_wise_alpha);
  AddRawSampleFaultCandidates(faults, pass.onsets, raw_samples.changes, epochs,
                              pass.forward.scalar_updates, scale, options.finder.family_wise_alpha);
  for (EffectCandidate& c : faults) others.push_back(std::move(c));
  for (EffectCandidate& c : WarmUpCandidates(pass.warm_ups, pass.forward.scalar_updates)) others.push_back(std::move(c));
  f.candidates = MergeCandidates(std::move(ranked.terms), f.structures, std::move(others),
                                 options.finder.family_wise_alpha);
  return f;
}

std::vector<DriftCorrelation> CorrelateDrifts(const ModelPass& pass, const AnalysisOptions& options,
                                              DecisionLog* decisions) {
  std::vector<std::string> notes;
  auto drifts = ident::CorrelateDrifts(pass.forward, pass.smoothed, *pass.layout, options.correlation,
                                       decisions != nullptr ? &notes : nullptr);
  if (decisions != nullptr) decisions->NoteEach(notes);
  return drifts;
}

Findings FindMissingEffects(const RunContext& c, const ModelPass& pass, const AnalysisOptions& options,
                            DecisionLog* decisions, const SettledStructures& settled) {
  return FindMissingEffects(c, pass, CorrelateDrifts(pass, options, decisions), options, decisions, settled);
}

bool AddsOnlyDeterministicEffects(const std::vector<std::string>& selectors) {
  return std::all_of(selectors.begin(), selectors.end(), [](const std::string& selector) {
    auto terms = ParseEffectSelector(selector);
    return terms.ok() && std::none_of(terms->begin(), terms->end(), [](const EffectTerm& t) {
             return t.family->kind == EffectKind::kRandom;
           });
  });
}

// The significant, identifiable candidate whose predicted ΔBIC is lowest,
// among single terms and whole families; nullptr when none is significant.
// A term and its family often score alike when one axis carries the effect;
// the family's extra parameters then cost more than they explain. When every
// axis carries it, the family explains far more than any term, and it is not
// mistaken for a look-alike term of another family (a common scale factor
// for two misalignments, say). Schwarz, Ann. Stat. 6(2), 1978.
const EffectCandidate* LowestBicSignificant(const std::vector<EffectCandidate>& terms,
                                            const std::vector<EffectCandidate>& families,
                                            const AnalysisOptions& options) {
  const EffectCandidate* best = nullptr;
  for (const auto* list : {&terms, &families}) {
    for (const EffectCandidate& c : *list) {
      if (!c.SignificantAt(options.finder.family_wise_alpha)) continue;
      if (best == nullptr || c.predicted_delta_bic < best->predicted_delta_bic) best = &c;
    }
  }
  // Of look-alike faults the run cannot tell apart, the likeliest (fault_findings.h).
  for (bool moved = best != nullptr; moved;) {
    moved = false;
    for (const EffectCandidate& c : terms) {
      if (IsLikelierLookAlike(*best, c, options.finder.family_wise_alpha)) {
        best = &c;
        moved = true;
      }
    }
  }
  return best;
}

// The effect `--discover` adds next.
const EffectCandidate* NextDiscovery(const Findings& found, const AnalysisOptions& options) {
  return LowestBicSignificant(found.candidates, found.families, options);
}

// The report of one scanned pass.
AnalysisReport ReportOf(const RunContext& c, const ModelPass& pass, const Findings& found,
                        const std::vector<ParameterEstimate>& identified, const DecisionLog& decisions) {
  AnalysisReport r;
  FillFit(pass, c.run, c.options, r);
  r.bench_motion = c.samples.bench_motion;
  DecisionLog fault_notes;
  ReportFaults(FaultFindings(c, pass, found, fault_notes), c.run.samples.back().t_s, r);
  r.effect_candidates = found.candidates;
  r.family_candidates = found.families;
  r.correlation = found.drifts;
  r.identified = identified;
  for (ParameterEstimate& e : WarmUpEstimates(pass)) r.identified.push_back(std::move(e));
  std::string unobservable;
  for (const ParameterEstimate& e : ConstantEffectEstimates(pass, c.run, c.reference_measurements)) {
    r.identified.push_back(e);
    if (ObservableByRun(e)) continue;
    unobservable += (unobservable.empty() ? "" : ", ") + e.name;
    if (std::abs(e.max_correlation) > kSeparableCorrelation) {
      unobservable += absl::StrFormat(" (only with %s: correlation %+.3f)", e.correlated_with, e.max_correlation);
    }
  }
  DecisionLog all = decisions;
  all.Append(fault_notes);
  if (!unobservable.empty()) {
    all.Note("not observable from this run (inseparable from another state, or a standard error above "
             "half the prior's): " + unobservable +
             "; a test that moves the unit through more positions or turns tells them");
  }
  r.notes = all.notes();
  r.decisions = all.decisions();
  return r;
}

}  // namespace insdiag::engine::pipeline
