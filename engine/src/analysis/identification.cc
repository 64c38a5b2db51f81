#include "analysis/identification.h"

#include <absl/strings/str_format.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <string_view>

#include "analysis/model_change.h"
#include "analysis/noise_identification.h"
#include "insdiag/engine/ident/correlation.h"
#include "insdiag/engine/ident/retarget.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine::pipeline {
namespace {

// The drift estimates' SEs made consistent with their likelihood ratio
// against `reference` (ident::WidenErrorsToTheLikelihoodRatio), with a note
// naming the drifts widened.
void WidenErrorsOrSay(const EpochRun& epochs, const ErrorModel& reference, ident::DriftLikelihoodResult& ml,
                      DecisionLog& decisions) {
  auto widened = ident::WidenErrorsToTheLikelihoodRatio(epochs, reference, ml);
  if (!widened.ok()) {
    decisions.Note("the drift estimates' standard errors were not checked against their likelihood ratio: " +
                    std::string(widened.status().message()));
    return;
  }
  if (widened->empty()) return;
  Decision d;
  d.kind = DecisionKind::kDriftErrorsWidened;
  d.subjects = *std::move(widened);
  d.adopted = true;
  decisions.Record(std::move(d));
}

// The drifts whose likelihood estimates the raw samples refuted: a note on
// each, and no earlier estimate of them kept (it was fitted as they were).
void NoteDriftsHeldByRawSamples(const ident::DriftLikelihoodResult& ml,
                                std::vector<ParameterEstimate>& identified,
                                DecisionLog& decisions) {
  for (const ident::HeldDrift& h : ml.held_by_raw_samples) {
    const std::string_view unit = UnitsOf(h.drift.sensor).rate;
    decisions.Note(
        absl::StrFormat("%s: the innovations' likelihood peaks at σ %.3g %s, τ %.3g s, whose Allan "
                        "variance at a cluster time of %.3g s is %.3g "
                        "times what the static segments' raw samples allow at the family-wise "
                        "level: the run's motion does not "
                        "tell this drift, and the model holds it at σ %.3g %s, τ %.3g s",
                        DriftName(h.drift), h.estimate.sigma, unit, h.estimate.tau_s,
                        h.excess.cluster_time_s, h.excess.ratio, h.held.sigma, unit, h.held.tau_s));
    std::erase_if(identified,
                  [&](const ParameterEstimate& q) { return DriftOfParameter(q.name) == h.drift; });
  }
}

// The likelihood-ratio statistic of the drift estimates against the model's
// values (one degree of freedom per identified parameter, σ or τ).
double DriftStatistic(const ident::DriftLikelihoodResult& ml) {
  return 2.0 * (ml.log_likelihood_after - ml.log_likelihood_before);
}

// Whether the drift estimates reject the model's values: 2Δℓ beyond χ²(m)
// at α for m identified parameters.
bool RejectsTheModelsValues(const ident::DriftLikelihoodResult& ml, double alpha) {
  return DriftStatistic(ml) >
         stats::ChiSquareQuantile(1.0 - alpha, static_cast<int>(ml.identified.size()));
}

// The likelihood's drift estimates (drift_likelihood.h) are reported; the
// model takes them when they raise the innovations' log-likelihood beyond
// the likelihood-ratio test of the model's values, χ²(m) at α for m
// identified parameters
// (Wilks, Ann. Math. Statist. 9(1), 1938) — as the correlation retargeting
// keeps a model the data do not contradict. True when the model took them.
// A model whose values are placeholders (an Allan-fit a-priori model: its τ
// a bound of the static segments) has nothing the data must overturn: it
// takes the estimates whatever the statistic.
bool ApplyDriftLikelihood(const ident::DriftLikelihoodResult& ml, double alpha, bool placeholders, ErrorModel& base,
                          std::vector<ParameterEstimate>& identified, DecisionLog& decisions) {
  if (!ml.not_identifiable.empty()) {
    Decision flat;
    flat.kind = DecisionKind::kDriftsNotIdentifiable;
    flat.subjects = ml.not_identifiable;
    decisions.Record(std::move(flat));
    // An earlier estimate of them (the common re-tune of an Allan fit's
    // placeholders) held everything else fixed: its standard error says
    // nothing of what the run cannot tell, so it is not reported.
    std::erase_if(identified, [&](const ParameterEstimate& q) {
      return std::find(ml.not_identifiable.begin(), ml.not_identifiable.end(), q.name) != ml.not_identifiable.end();
    });
  }
  NoteDriftsHeldByRawSamples(ml, identified, decisions);
  if (ml.identified.empty()) return false;
  for (const ParameterEstimate& p : ml.identified) {
    std::erase_if(identified, [&](const ParameterEstimate& q) { return q.name == p.name; });
    identified.push_back(p);
  }
  const bool rejects = RejectsTheModelsValues(ml, alpha);
  const bool takes = rejects || placeholders;
  if (takes) base = ml.model;
  Decision d;
  d.kind = DecisionKind::kDriftsIdentified;
  d.statistic = DriftStatistic(ml);
  d.degrees_of_freedom = static_cast<int>(ml.identified.size());
  d.level = alpha;
  d.adopted = takes;
  d.measures = {{"iterations", ml.iterations}, {"filter_passes", ml.filter_passes}};
  for (const ParameterEstimate& p : ml.identified) d.subjects.push_back(p.name);
  if (!ml.converged) d.qualifiers.emplace_back("not_converged");
  if (takes && !rejects) d.qualifiers.emplace_back("placeholders");
  if (placeholders) d.qualifiers.emplace_back("allan_fit_prior");
  decisions.Record(std::move(d));
  return takes;
}

// Where the retargeting loop stopped.
struct Retargeted {
  std::vector<DriftCorrelation> drifts;  // correlation processing of the last pass
  bool faults_flagged = false;           // by the last pass's monitoring or onset scan
  bool drifts_by_likelihood = false;     // the misfit was the drifts': their σ and τ are in the model
  bool deferred = false;                 // the a-priori model's missing effects go first
  // The faults to test against the drifts identified beside them, where the
  // drifts were identified from a class prior (an Allan fit's placeholders,
  // or a nominal model whose drifts the run overturned): the most
  // significant bias step and ramp the first pass found against the
  // a-priori model (family-wise over the fault terms), then those of the
  // identified drifts' own scan (AddFaultsOfTheIdentifiedDrifts).
  std::vector<OnsetFit> faults_to_test;
  int fault_terms_scanned = 0;

  // Whether the drifts were identified from a class prior (an Allan fit, a
  // unit type's nominal model) rather than re-tuned from the unit's own
  // datasheet: a fault may be inside them. A datasheet's drifts re-tuned by
  // likelihood stay the unit's specification: a fault tested against drifts
  // the datasheet does not allow would be credited with their misfit.
  bool DriftsFromAClassPrior(const APriori& a_priori) const {
    return a_priori.FromAllanFit() || (drifts_by_likelihood && !a_priori.FromDatasheet());
  }

  // Whether the final identification holds the drifts back because faults
  // were flagged: a wider drift would hide the fault the diagnosis is for.
  // An Allan fit's placeholders are not held: what they flag says how far
  // they are from the unit, not that it failed.
  bool HoldsDriftsForFlaggedFaults(const APriori& a_priori) const {
    return faults_flagged && !a_priori.FromAllanFit();
  }

  // Whether the drifts held for flagged faults are a class prior's: a unit
  // type's nominal model, no datasheet of the unit's own. Whether the
  // faults or wider drifts explain the flags is then a test (as where the
  // run overturned the nominal drifts), not a given: a unit whose drift σ
  // tripled trips the monitor as a fault would.
  bool HoldsAClassPriorsDriftsForFlaggedFaults(const APriori& a_priori) const {
    return HoldsDriftsForFlaggedFaults(a_priori) && !a_priori.FromDatasheet();
  }

  // Whether both sides of a fault's test identify drifts the model's own
  // final identification left: the set the misfit's competition took, or
  // the drifts held for flagged faults.
  bool FaultTestIdentifiesMoreDrifts(const APriori& a_priori) const {
    return drifts_by_likelihood || HoldsDriftsForFlaggedFaults(a_priori);
  }
};

// The most significant bias step and the most significant ramp among the
// scanned faults that pass `keep`: a step and a ramp of one axis look alike
// against drifts that are not the unit's.
template <typename Keep>
std::vector<OnsetFit> MostSignificantStepAndRamp(const std::vector<OnsetFit>& onsets, Keep keep) {
  std::vector<OnsetFit> out;
  for (const bool step : {true, false}) {
    const OnsetFit* best = nullptr;
    for (const OnsetFit& f : onsets) {
      if (!f.identifiable || !keep(f) || (f.term.family->regressor == Regressor::kStep) != step)
        continue;
      if (best == nullptr || f.p_value < best->p_value) best = &f;
    }
    if (best != nullptr) out.push_back(*best);
  }
  return out;
}

// The drifts' σ and τ by likelihood from the a-priori values and from
// starts a decade either side, those worth their parameters by BIC, their
// standard errors checked against the likelihood ratio.
absl::StatusOr<ident::DriftLikelihoodResult> DriftsFromStarts(const RunContext& c,
                                                              const ErrorModel& model,
                                                              DecisionLog& decisions) {
  auto ml =
      ident::IdentifyDriftsFromStarts(c.epochs, model, c.a_priori.model, DriftSelection::Every(),
                                      c.a_priori.drift_starts, c.drift_ceilings, c.options.drift_likelihood);
  if (ml.ok()) ml = ident::KeepDriftsWorthTheirParameters(c.epochs, model, *std::move(ml));
  if (ml.ok()) WidenErrorsOrSay(c.epochs, c.a_priori.model, *ml, decisions);
  return ml;
}

// The drifts' σ and τ identified with the best candidate in the model.
absl::StatusOr<ident::DriftLikelihoodResult> DriftsBesideTheCandidate(const RunContext& c,
                                                                      const ModelPass& pass,
                                                                      const Findings& found,
                                                                      const EffectCandidate& best,
                                                                      const ErrorModel& base) {
  auto with_candidate = ExtendModel(c.run, base, {best.name}, pass.scan.get(), found, c.options);
  if (!with_candidate.ok()) return with_candidate.status();
  DecisionLog fit_notes;
  return DriftsFromStarts(c, *with_candidate, fit_notes);
}

// Whether the drifts of a class prior are off beside the best candidate as
// well: the drifts identified with the candidate in the model (`beside`),
// against the model with the candidate alone (χ² at the family-wise level, as
// ApplyDriftLikelihood). A unit can be both far from its type's drifts and
// faulty; the comparison of the two explanations alone picks one, and
// drifts left at the type's nominal beside a fault leave a misfit that the
// scan reads as walks and steps on every sensor, ranking the fault among them.
bool DriftsOffBesideTheCandidate(const RunContext& c,
                                 const absl::StatusOr<ident::DriftLikelihoodResult>& beside) {
  return beside.ok() && !beside->identified.empty() &&
         RejectsTheModelsValues(*beside, c.options.monitor.family_wise_alpha);
}

// The a-priori model's misfit against its best missing effect: a drift whose
// σ is far larger than the model's shows as effects that follow the table's
// motion (a g-sensitivity, say). The two explanations compete by BIC
// (Schwarz, Ann. Stat. 6(2), 1978): every drift's σ and τ by likelihood,
// from the a-priori values and from starts a decade either side — a unit far
// from its type's nominal model is the case this is for — against the best
// candidate's predicted ΔBIC. Also when faults are flagged: a drift far wider
// than the model's trips the monitor and the onset scan as a jump would, and
// BIC decides which it is. Where the candidate wins and the drifts are a
// class prior's, the drifts are identified again beside it: a unit can be
// both far from its type and faulty. True when the model took the drifts.
bool ChooseDriftsOverTheBestCandidate(const RunContext& c, const ModelPass& pass,
                                      const Findings& found, const EffectCandidate& best,
                                      ErrorModel& base, std::vector<ParameterEstimate>& identified,
                                      DecisionLog& decisions) {
  const AnalysisOptions& options = c.options;
  const double log_n = std::log(static_cast<double>(std::max(1, pass.forward.scalar_updates)));
  auto ml = DriftsFromStarts(c, base, decisions);
  if (!ml.ok()) {
    decisions.Note("the drifts were not identified against the candidates: " + std::string(ml.status().message()));
    return false;
  }
  if (ml->identified.empty()) {
    decisions.Note("no drift's σ and τ by likelihood are worth their parameters against the candidates");
    return false;
  }
  const double drift_bic = -DriftStatistic(*ml) + static_cast<double>(ml->identified.size()) * log_n;
  // The drifts against the best candidate by ΔBIC: the candidate is the
  // alternative a drift explanation rejects.
  const auto over_candidate = [&](bool adopted, std::vector<std::string> qualifiers,
                                  std::vector<std::pair<std::string, double>> measures) {
    Decision d;
    d.kind = DecisionKind::kDriftsOverCandidate;
    d.statistic = drift_bic;
    d.adopted = adopted;
    d.rejected = {{best.name, best.predicted_delta_bic}};
    d.measures = std::move(measures);
    d.qualifiers = std::move(qualifiers);
    for (const ParameterEstimate& p : ml->identified) d.subjects.push_back(p.name);
    decisions.Record(std::move(d));
  };
  if (drift_bic < best.predicted_delta_bic &&
      ApplyDriftLikelihood(*ml, options.monitor.family_wise_alpha, c.a_priori.FromAllanFit(), base, identified, decisions)) {
    over_candidate(true, {}, {});
    return true;
  }
  // What the likelihood measures of the drifts beside a fault: a jump or a
  // ramp from an onset is not a stationary drift's variance, and drifts
  // identified without it take it on: a jump reads as a wider, far slower
  // drift of its own sensor, and the tilt it leaves as other sensors' drifts.
  const EffectFamily* family = FindEffectFamily(best.family);
  const bool fault = family != nullptr && family->kind == EffectKind::kFault;
  std::optional<absl::StatusOr<ident::DriftLikelihoodResult>> beside;
  if (!c.a_priori.FromDatasheet() || fault) {
    beside = DriftsBesideTheCandidate(c, pass, found, best, base);
    if (!beside->ok()) {
      decisions.Note("the drifts were not identified beside " + best.name + ": " +
                      std::string(beside->status().message()));
    }
  }
  // A unit far from its type can be faulty too. The model then takes the
  // drifts' own estimates, not those beside the candidate (a walk beside a
  // drift takes its slow part: that drift alone would be left too narrow),
  // and the candidate is scanned again against them; a fault among the
  // candidates is tested against the drifts identified beside it.
  if (!c.a_priori.FromDatasheet() && DriftsOffBesideTheCandidate(c, *beside)) {
    const double statistic = DriftStatistic(**beside);
    const auto dof = static_cast<int>((*beside)->identified.size());
    decisions.Note(absl::StrFormat(
        "the drifts' σ and τ identified beside %s (%d parameters, EM %d iterations, "
        "%d filter passes) still raise the likelihood by 2Δℓ = %.1f, beyond χ²(%d) at %.2g: "
        "the a-priori model's misfit is its drifts as well",
        best.name, dof, (*beside)->iterations, (*beside)->filter_passes, statistic, dof,
        options.monitor.family_wise_alpha));
    if (ApplyDriftLikelihood(*ml, options.monitor.family_wise_alpha, c.a_priori.FromAllanFit(), base,
                             identified, decisions)) {
      over_candidate(true, {"beside_the_candidate_too"}, {});
      return true;
    }
  }
  // The drifts stay as the a-priori model has them, but what the likelihood
  // measured of them is reported: a drift far from its nominal is evidence
  // for the diagnosis whichever explanation wins. Beside a fault, the
  // drifts identified with it in the model. Beside any other candidate, the
  // drifts' own estimates: a term that follows the table's motion is how a
  // wider drift shows on a multi-position test (it scores as a
  // g-sensitivity, and beside that term the drift looks nominal), and a walk
  // shares the drift's slow variance.
  const ident::DriftLikelihoodResult* reported = !fault ? &*ml : beside->ok() ? &**beside : nullptr;
  if (reported == nullptr) return false;
  for (const ParameterEstimate& p : reported->identified) {
    std::erase_if(identified, [&](const ParameterEstimate& q) { return q.name == p.name; });
    identified.push_back(p);
  }
  const auto parameters = static_cast<double>(ml->identified.size());
  if (!fault) {
    over_candidate(false, {}, {{"parameters", parameters}});
  } else if (reported->identified.empty()) {
    over_candidate(false, {"none_beside_the_fault"}, {{"parameters", parameters}});
  } else {
    over_candidate(false, {"reported_beside_the_fault"},
                   {{"parameters", parameters},
                    {"parameters_beside_the_fault", static_cast<double>(reported->identified.size())}});
  }
  return false;
}

// Retargeting: a pass, correlation processing of its smoothed drifts, a
// re-tuned model, until the parameters settle. The first pass also scans for
// missing effects: parameters identified under a model whose structure is
// wrong soak up the missing effect (a drift widened to carry a scale-factor
// error), so the retargeting waits until the structure is complete.
absl::StatusOr<Retargeted> Retarget(const RunContext& c, Identification& id, DecisionLog& decisions) {
  const AnalysisOptions& options = c.options;
  Retargeted out;
  for (int it = 0; it < options.max_retarget_iterations; ++it) {
    Progress(options, 0.1 + 0.5 * it / options.max_retarget_iterations, "retargeting");
    const bool first = it == 0;
    auto pass = RunPass(c.run, c.epochs, id.model, c.samples, options, /*with_scan=*/first);
    if (!pass.ok()) return pass.status();
    // An a-priori model from the Allan fit is not a specification to
    // protect: its drift τ is a bound of the static segments (the longest τ
    // analysed) or a guess from them, and its misfit shows as effects. Its
    // drifts are re-tuned by the whole run before the scan.
    const bool scan_a_priori = first && !c.a_priori.FromAllanFit();
    DecisionLog found_notes;
    out.drifts = CorrelateDrifts(*pass, options, scan_a_priori ? &found_notes : nullptr);
    // A bias step or ramp the onset scan finds counts too (Bonferroni over its terms).
    const auto family_wise = [&](const OnsetFit& f) {
      return f.p_value * static_cast<double>(pass->onsets.size()) < options.finder.family_wise_alpha;
    };
    out.faults_flagged = !pass->monitor.faults.empty() || std::any_of(pass->onsets.begin(), pass->onsets.end(), family_wise);
    if (first) {
      out.faults_to_test = MostSignificantStepAndRamp(pass->onsets, family_wise);
      out.fault_terms_scanned = static_cast<int>(pass->onsets.size());
    }
    // The a-priori model's missing effects, the likelihood's structures
    // among them: a walk is a missing effect as much as a constant term,
    // and a drift σ re-tuned before it is tested takes the walk's slow
    // variance (a wider or slower drift over the run), which the walk's
    // nested test then cannot tell from it.
    Findings found;
    const EffectCandidate* best = nullptr;
    if (scan_a_priori) {
      found = FindMissingEffects(c, *pass, out.drifts, options, &found_notes);
      best = LowestBicSignificant(found.candidates, found.families, options);
    }
    if (best != nullptr) {
      if (ChooseDriftsOverTheBestCandidate(c, *pass, found, *best, id.model, id.identified, decisions)) {
        out.drifts_by_likelihood = true;
        continue;
      }
      decisions.Note("the a-priori model lacks significant effects: the drift and reference-noise parameters "
                      "are not re-tuned on this model (they would absorb what the effects explain); they are "
                      "identified when the analysis starts from a model with the effects (baseline effects)");
      id.scanned = ScannedModel{std::move(*pass), std::move(found), std::move(found_notes)};
      out.deferred = true;
      return out;
    }
    ident::RetargetResult step = ident::RetargetDrifts(id.model, c.a_priori.model, out.drifts,
                                                       options.settle_log_ratio, options.monitor.family_wise_alpha);
    // Drifts from a class prior (an Allan fit's placeholders, a bound or a
    // guess from the static segments; a nominal model the run overturned):
    // innovations beyond them are the drifts' misfit, or a fault's, before
    // they are noise of the bench's reference, and a reference noise raised
    // to absorb them flattens the likelihood the drifts and the faults are
    // then tested by. Such a model's reference is fitted once its drifts
    // have their likelihood values (FitReferenceNoiseToTheIdentifiedModel).
    const bool reference_changed =
        !out.DriftsFromAClassPrior(c.a_priori) &&
        FitReferenceNoiseTheInnovationsReject(c, pass->forward, pass->model, step.model, decisions);
    // Nothing significant: the report's scan when nothing below re-tunes
    // the model (the unit's a-priori model fits), else a new one.
    if (scan_a_priori) id.scanned = ScannedModel{std::move(*pass), std::move(found), std::move(found_notes)};
    id.model = step.model;
    // The correlation estimates replace those of the drifts they re-tune. A
    // drift this pass did not resolve keeps its value in the model, and so
    // the estimate that gave it (an earlier pass's, or the likelihood's).
    std::erase_if(id.identified, [&](const ParameterEstimate& p) {
      return std::any_of(step.identified.begin(), step.identified.end(),
                         [&](const ParameterEstimate& q) { return q.name == p.name; });
    });
    id.identified.insert(id.identified.end(), step.identified.begin(), step.identified.end());
    if (step.settled && !reference_changed) break;
    if (it + 1 == options.max_retarget_iterations) {
      decisions.Note("the identified drift parameters had not settled after " +
                      std::to_string(options.max_retarget_iterations) + " iterations");
    }
  }
  return out;
}

// The drifts by the innovations' likelihood (drift_likelihood.h), one of two
// sets. The drifts correlation processing left unresolved: their σ (τ held at
// the model's value, which the run does not tell — unless it is an Allan-fit
// placeholder, a bound or a guess from static segments shorter than the
// drift's τ). The drifts it resolved: σ and τ, from its estimates (which the
// retargeted model holds where the data rejected the a-priori values), a
// start near the likelihood's ridge. Apart, because one EM over both sets
// crawls: on an eight-hour run with a tripled gyro σ it had not converged
// after 30 steps, that σ still 15 % short.
absl::StatusOr<ident::DriftLikelihoodResult> IdentifyDriftSet(const RunContext& c,
                                                              const ErrorModel& model,
                                                              const Retargeted& retargeted,
                                                              bool resolved_set,
                                                              bool both_sides_of_a_fault_test) {
  Progress(c.options, 0.6, "maximum-likelihood drift identification");
  const DriftSelection resolved = ResolvedDrifts(retargeted.drifts);
  DriftSelection selection, tau_too;
  for (const DriftAxis d : DriftAxis::All()) {
    // Not on either side of a fault's test against the drifts: the fault is
    // in the model on one side.
    const bool keep_for_faults =
        !both_sides_of_a_fault_test && retargeted.HoldsDriftsForFlaggedFaults(c.a_priori);
    selection.Set(d, !keep_for_faults && resolved.Contains(d) == resolved_set);
    tau_too.Set(d, selection.Contains(d) && (resolved_set || c.a_priori.FromAllanFit()));
  }
  if (c.a_priori.drift_starts.grid_tau_points > 0) {
    return ident::IdentifyDriftsFromGrid(c.epochs, model, c.a_priori.model, selection, tau_too,
                                         c.a_priori.drift_starts, c.drift_ceilings, c.options.drift_likelihood);
  }
  return ident::IdentifyDriftsByLikelihood(c.epochs, model, c.a_priori.model, selection, tau_too,
                                           c.drift_ceilings, c.options.drift_likelihood);
}

// The drifts' final values, by likelihood: correlation processing of the
// smoothed estimates gives the drifts' structure and a start, but the
// smoother's shrinkage biases its σ and τ low together along the fit's ridge
// (docs/IDENTIFICATION.md, coverage); the likelihood's estimates carry no
// such bias and their intervals cover the truth. The unresolved set is done
// already when the misfit's competition took it, except on either side of a
// fault's test against the drifts: a drift that took the fault in is
// identified again beside it, and the model without the fault is fitted alike.
void IdentifyFinalDrifts(const RunContext& c, const Retargeted& retargeted, Identification& id,
                         DecisionLog& decisions, bool both_sides_of_a_fault_test = false) {
  for (const bool resolved_set : {false, true}) {
    if (!resolved_set && retargeted.drifts_by_likelihood && !both_sides_of_a_fault_test) continue;
    auto ml = IdentifyDriftSet(c, id.model, retargeted, resolved_set, both_sides_of_a_fault_test);
    if (ml.ok()) WidenErrorsOrSay(c.epochs, c.a_priori.model, *ml, decisions);
    if (!ml.ok()) {
      decisions.Note("the drifts were not identified by likelihood: " + std::string(ml.status().message()));
    } else {
      ApplyDriftLikelihood(*ml, c.options.monitor.family_wise_alpha, c.a_priori.FromAllanFit(), id.model, id.identified,
                           decisions);
    }
  }
}

// A bias step or ramp found against a class prior's drifts, tested against
// the drifts identified without it. Drifts identified from starts decades
// apart take a step as a slower, wider drift, and the step's scan on that
// model falls below its level, so the drifts are identified again with the fault in the model
// at the scan's onset, and the two fitted likelihoods decide: the fault
// stands when 2Δℓ exceeds the onset scan's own bound (Davies over the onsets,
// Bonferroni over the fault terms) — the likelihood ratio fitted on both
// sides. Model A then has the drifts identified beside the fault, without
// it: the scan names the fault, and adding it is the user's step, as for any
// unit.
struct FaultAgainstDriftsTest {
  const OnsetFit* fault = nullptr;
  Identification with_fault;  // the drifts identified beside it (the fault in the model)
  DecisionLog decisions;
  double statistic = 0.0;
  double p_value = 1.0;
  bool tested = false;
};

FaultAgainstDriftsTest TestFaultAgainstDrifts(const RunContext& c, const Retargeted& retargeted,
                                              const OnsetFit& fault, const Identification& id,
                                              double log_likelihood_without) {
  FaultAgainstDriftsTest t;
  t.fault = &fault;
  t.with_fault.model = id.model;
  t.with_fault.identified = id.identified;
  t.with_fault.model.effects.push_back(
      FaultEffectAt(fault.term, fault.onset_s, fault.estimate, fault.std_error, c.options));
  IdentifyFinalDrifts(c, retargeted, t.with_fault, t.decisions, /*both_sides_of_a_fault_test=*/true);
  auto with = ProfileLogLikelihood(c.epochs, t.with_fault.model);
  if (!with.ok()) {
    t.decisions = DecisionLog{};
    t.decisions.Note(fault.term.Name() + " against the identified drifts: not tested (" +
                     std::string(with.status().message()) + ")");
    return t;
  }
  t.tested = true;
  t.statistic = std::max(0.0, 2.0 * (*with - log_likelihood_without));
  t.p_value =
      std::min(1.0, OnsetPValue(t.statistic, fault.path_length) * static_cast<double>(retargeted.fault_terms_scanned));
  t.with_fault.model.effects.pop_back();
  return t;
}

// The faults the drifts identified from a class prior may have taken in. A
// bias step inside the static segments raises their Allan curve
// as a rate random walk does (a step's Allan variance grows with the cluster
// time), so the placeholder drift is already wide and slow, the first scan
// does not flag the step, and the drifts identified from there keep it as a
// slower drift, the step's scan on that model below its level. The identified model's own
// onset scan still peaks near the step: its most significant step and ramp
// not tested already join the faults tested against the drifts identified
// beside them, whose level decides. Each costs one drift identification.
void AddFaultsOfTheIdentifiedDrifts(const RunContext& c, const ErrorModel& model,
                                    const ForwardPass& forward, Retargeted& retargeted) {
  const std::vector<OnsetFit> onsets = ScanOnsets(forward, StateLayout(model), c.epochs,
                                                  AbsentFaultTerms(model), c.options.onset_scan);
  const auto not_tested = [&](const OnsetFit& f) {
    return std::none_of(retargeted.faults_to_test.begin(), retargeted.faults_to_test.end(),
                        [&](const OnsetFit& g) { return g.term == f.term; });
  };
  for (OnsetFit& f : MostSignificantStepAndRamp(onsets, not_tested)) {
    retargeted.faults_to_test.push_back(std::move(f));
  }
  retargeted.fault_terms_scanned = static_cast<int>(onsets.size());
}

// The faults found against the a-priori drifts, each against the identified
// drifts; model A takes the drifts identified beside the one whose fitted
// 2Δℓ is largest among those that stand, or, of those within 2 of it that
// the run cannot tell apart, the one its sensor's raw samples show
// (finder/fault_findings.h, IsLikelierLookAlike).
// True when a fault stands.
bool TestFaultsAgainstDrifts(const RunContext& c, const Retargeted& retargeted,
                             double log_likelihood_without, Identification& id,
                             DecisionLog& decisions) {
  FaultAgainstDriftsTest* best = nullptr;
  std::vector<FaultAgainstDriftsTest> tests;
  for (const OnsetFit& f : retargeted.faults_to_test) {
    tests.push_back(TestFaultAgainstDrifts(c, retargeted, f, id, log_likelihood_without));
  }
  for (FaultAgainstDriftsTest& t : tests) {
    if (!t.tested) {
      decisions.Append(t.decisions);
      continue;
    }
    const bool stands = t.p_value < c.options.finder.family_wise_alpha;
    Decision d;
    d.kind = DecisionKind::kFaultAgainstDrifts;
    d.subjects = {t.fault->term.Name()};
    d.statistic = t.statistic;
    d.degrees_of_freedom = 1;
    d.level = c.options.finder.family_wise_alpha;
    d.p_value = t.p_value;
    d.adopted = stands;
    d.measures = {{"onset_s", t.fault->onset_s}};
    decisions.Record(std::move(d));
    if (stands && (best == nullptr || t.statistic > best->statistic)) best = &t;
  }
  if (best == nullptr) return false;
  if (SeenInRawSamples(*best->fault, c.raw_samples.changes) == nullptr) {
    FaultAgainstDriftsTest* seen = nullptr;
    for (FaultAgainstDriftsTest& t : tests) {
      if (t.tested && t.p_value < c.options.finder.family_wise_alpha &&
          best->statistic - t.statistic < kIndistinguishableDeltaBic &&
          AreLookAlikes(*best->fault, *t.fault) &&
          SeenInRawSamples(*t.fault, c.raw_samples.changes) != nullptr &&
          (seen == nullptr || t.statistic > seen->statistic)) {
        seen = &t;
      }
    }
    if (seen != nullptr) best = seen;
  }
  decisions.Note("model A has the drifts identified beside " + best->fault->term.Name());
  decisions.Append(best->decisions);
  id.model = std::move(best->with_fault.model);
  id.identified = std::move(best->with_fault.identified);
  return true;
}

// The faults of a class prior's drifts and of the drifts identified from
// them, each tested against the drifts identified beside it; one
// forward pass of the identified model serves the scan and the likelihood
// the tests are against. Drifts held for flagged faults of which none
// stands take their own estimates: they were held for nothing.
void TestFaultsAgainstTheIdentifiedDrifts(const RunContext& c, Retargeted& retargeted,
                                          Identification& id, DecisionLog& decisions) {
  auto forward = RunForwardFilter(c.epochs, id.model);
  if (!forward.ok()) {
    decisions.Note("faults against the drifts identified from a class prior: not tested (" +
                    std::string(forward.status().message()) + ")");
    return;
  }
  AddFaultsOfTheIdentifiedDrifts(c, id.model, *forward, retargeted);
  if (retargeted.faults_to_test.empty()) return;
  double log_likelihood_without = ProfileLogLikelihood(*forward, id.model);
  // Where the fault's side identifies drifts the model's own identification
  // left, the side without the fault is fitted alike: else the statistic
  // counts what those drifts gain as the fault's, and a healthy unit's ramp
  // stands on the drifts' gain.
  std::optional<Identification> without;
  DecisionLog without_notes;
  if (retargeted.FaultTestIdentifiesMoreDrifts(c.a_priori)) {
    without = Identification{};
    without->model = id.model;
    without->identified = id.identified;
    IdentifyFinalDrifts(c, retargeted, *without, without_notes, /*both_sides_of_a_fault_test=*/true);
    if (auto l = ProfileLogLikelihood(c.epochs, without->model); l.ok()) {
      log_likelihood_without = std::max(log_likelihood_without, *l);
    }
  }
  const bool a_fault_stands = TestFaultsAgainstDrifts(c, retargeted, log_likelihood_without, id, decisions);
  if (!a_fault_stands && without.has_value() && retargeted.HoldsDriftsForFlaggedFaults(c.a_priori)) {
    decisions.Note(
        "no flagged fault stands against the drifts identified beside it: model A has the drifts "
        "identified without one");
    decisions.Append(without_notes);
    id.model = std::move(without->model);
    id.identified = std::move(without->identified);
  }
}

}  // namespace

absl::StatusOr<Identification> IdentifyModel(const RunContext& c, const std::optional<ident::AllanResult>& allan,
                                             ErrorModel base, DecisionLog& decisions) {
  Identification id;
  if (allan.has_value()) id.identified = ApplyAllanNoise(c, *allan, base);
  KeepQuantisationTheInnovationsSupport(c, QuantisationTest::kBeforeTheDrifts, base, id.identified,
                                        decisions);
  RetuneUnresolvedNoise(c, allan, base, id.identified, decisions);
  id.model = std::move(base);
  auto retargeted = Retarget(c, id, decisions);
  if (!retargeted.ok()) return retargeted.status();
  if (!retargeted->deferred) {
    IdentifyFinalDrifts(c, *retargeted, id, decisions);
    // Drifts re-tuned from the unit's own specification keep what the scan finds beside them.
    if (retargeted->DriftsFromAClassPrior(c.a_priori) ||
        retargeted->HoldsAClassPriorsDriftsForFlaggedFaults(c.a_priori))
      TestFaultsAgainstTheIdentifiedDrifts(c, *retargeted, id, decisions);
    KeepQuantisationTheInnovationsSupport(c, QuantisationTest::kAfterTheDrifts, id.model,
                                          id.identified, decisions);
  }
  if (retargeted->DriftsFromAClassPrior(c.a_priori) && !retargeted->deferred) {
    if (auto fitted = FitReferenceNoiseToTheIdentifiedModel(c, id.model, decisions); !fitted.ok())
      return fitted;
  }
  return id;
}

}  // namespace insdiag::engine::pipeline
