#include "insdiag/engine/decision.h"

#include <algorithm>
#include <string>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "insdiag/engine/ident/retarget.h"

namespace insdiag::engine {
namespace {

std::string Names(const Decision& d) { return absl::StrJoin(d.subjects, ", "); }

double MeasureOr(const Decision& d, std::string_view name, double otherwise = 0.0) {
  return d.Measure(name).value_or(otherwise);
}

std::string DriftsIdentified(const Decision& d) {
  const bool placeholders = d.Qualified("placeholders");
  return "drift parameters identified by likelihood of the innovations: " + Names(d) +
         absl::StrFormat(" (EM, %d iterations%s, %d filter passes): 2Δℓ = %.1f against χ²(%d) at %.2g — ",
                         static_cast<int>(MeasureOr(d, "iterations")),
                         d.Qualified("not_converged") ? ", not converged" : "",
                         static_cast<int>(MeasureOr(d, "filter_passes")), d.statistic, d.degrees_of_freedom,
                         d.level) +
         (!d.adopted       ? "the data do not reject the model's values, kept"
          : placeholders   ? "the model's values were the Allan fit's placeholders: it takes the estimates"
                           : "the model takes the estimates");
}

std::string DriftsOverCandidate(const Decision& d) {
  const WeighedAlternative& best = d.rejected.empty() ? WeighedAlternative{} : d.rejected.front();
  if (d.adopted && d.Qualified("beside_the_candidate_too")) {
    return absl::StrFormat(
        "the model takes the drifts' own estimates (ΔBIC %.1f; the best candidate's %.1f) and is scanned again",
        d.statistic, best.statistic);
  }
  if (d.adopted) {
    return absl::StrFormat(
        "the a-priori model's misfit is the drifts' σ rather than a missing effect (ΔBIC %.1f against the best "
        "candidate's %.1f): the model takes them and is scanned again",
        d.statistic, best.statistic);
  }
  // The candidates stand: the drift estimates are reported, not taken.
  const std::string standing = absl::StrFormat(
      "the drifts' σ and τ by likelihood (%d parameters worth their cost) reach ΔBIC %.1f "
      "against the best candidate's %.1f: the candidates stand",
      static_cast<int>(MeasureOr(d, "parameters")), d.statistic, best.statistic);
  if (d.Qualified("none_beside_the_fault")) {
    return standing + "; beside " + best.name + " no drift's σ and τ are worth their parameters";
  }
  if (d.Qualified("reported_beside_the_fault")) {
    return standing + absl::StrFormat(", and the drift estimates identified beside %s (%d parameters) "
                                      "are reported beside the a-priori model's values",
                                      best.name, static_cast<int>(MeasureOr(d, "parameters_beside_the_fault")));
  }
  return standing + ", and the drift estimates are reported beside the a-priori model's values";
}

std::string ReferenceNoiseRaised(const Decision& d) {
  std::string changes;
  for (const std::string& group : d.subjects) {
    const auto* g = std::find_if(ident::kReferenceChannelGroups.begin(), ident::kReferenceChannelGroups.end(),
                                 [&](const ident::ReferenceChannelGroup& r) { return r.name == group; });
    const std::string_view unit = g != ident::kReferenceChannelGroups.end() ? g->unit : "";
    absl::StrAppendFormat(&changes, "%s%s %.3g → %.3g %s", changes.empty() ? "" : ", ", group,
                          MeasureOr(d, group + ".before"), MeasureOr(d, group + ".after"), unit);
  }
  if (d.adopted) {
    return absl::StrFormat(
        "the innovations exceed their predicted variance: the reference noise was raised by "
        "maximum likelihood (%s; 2Δℓ = %.1f against χ²(%d) at %.2g) — the unit moved in ways "
        "the bench's reference did not record (sway, vibration)",
        changes, d.statistic, d.degrees_of_freedom, d.level);
  }
  return absl::StrFormat(
      "the innovations exceed their predicted variance, but not as a noise of the bench's "
      "reference: its likelihood's best value%s gains 2Δℓ = %.1f against χ²(%d) at %.2g; "
      "the reference accuracy is kept",
      changes.empty() ? "" : " (" + changes + ")", d.statistic, d.degrees_of_freedom, d.level);
}

std::string NoiseRetuned(const Decision& d) {
  const char* origin = d.Qualified("resolved_by_the_allan_fit") ? ", resolved by the Allan fit of the raw samples): "
                                  : d.Qualified("seeded_by_the_allan_fit")
                                      ? ", seeded by the Allan fit, not resolved by correlation processing): "
                                      : ", set from Allan bounds): ";
  return absl::StrCat("re-tuned by maximum likelihood of the innovations, ", d.scope, " (", Names(d), origin,
                      absl::StrFormat("× %.3g (SE of ln: %.2g)%s", MeasureOr(d, "scale"), MeasureOr(d, "log_std_error"),
                                      d.Qualified("at_the_search_limit") ? ", at the search range's limit" : ""));
}

std::string QuantisationKept(const Decision& d) {
  std::string axes;
  for (const std::string& name : d.subjects) {
    absl::StrAppendFormat(&axes, "%s%c %.3g m/s", axes.empty() ? "" : ", ", name.back(), MeasureOr(d, name));
  }
  const char* against = d.Qualified("before_the_drifts") ? "the a-priori drifts" : "the identified drifts";
  if (d.adopted) {
    return absl::StrFormat(
        "the Allan fit's accelerometer quantisation (%s) is in the model: with %s the innovations' likelihood "
        "prefers it, 2Δℓ = %.1f",
        axes, against, d.statistic);
  }
  return absl::StrFormat(
      "the Allan fit's accelerometer quantisation (%s) is not in the model: with %s the innovations' likelihood "
      "is higher without it (2Δℓ = %.1f); over the static segments' few short cluster times it stood for the "
      "white noise and the drift's rise",
      axes, against, -d.statistic);
}

std::string APrioriModel(const Decision& d) {
  if (d.Qualified("datasheet")) {
    return "the a-priori model is the run's datasheet: its drifts are the unit's own specification";
  }
  if (d.Qualified("nominal")) {
    return "the a-priori model is the nominal model given for the unit (its unit type's, or the request's): a "
           "class prior the drift identification searches from";
  }
  if (d.Qualified("earlier_analysis")) {
    return "model A is the model an earlier analysis of this run identified: it was not identified again";
  }
  if (d.Qualified("no_specification")) {
    return "the run has no complete datasheet and no nominal model: the a-priori model comes from its Allan "
           "deviation";
  }
  return "the a-priori model comes from the run's Allan deviation";
}

}  // namespace

std::optional<double> Decision::Measure(std::string_view name) const {
  for (const auto& [n, v] : measures) {
    if (n == name) return v;
  }
  return std::nullopt;
}

bool Decision::Qualified(std::string_view qualifier) const {
  return std::find(qualifiers.begin(), qualifiers.end(), qualifier) != qualifiers.end();
}

std::string RenderNote(const Decision& d) {
  switch (d.kind) {
    case DecisionKind::kDriftsIdentified:
      return DriftsIdentified(d);
    case DecisionKind::kDriftsNotIdentifiable:
      return "not identifiable with this run's motion (the innovations' likelihood is flat in them): " + Names(d);
    case DecisionKind::kDriftErrorsWidened:
      return "standard errors widened to the likelihood ratio against the a-priori values (the curvature at "
             "the estimate understated how flat the likelihood stays along the σ–τ ridge): " +
             Names(d);
    case DecisionKind::kDriftsOverCandidate:
      return DriftsOverCandidate(d);
    case DecisionKind::kFaultAgainstDrifts:
      return absl::StrFormat(
          "%s at %.0f s, tested with the drifts identified beside it: 2Δℓ = %.1f (p = "
          "%.2g over the onsets and fault terms) — %s",
          Names(d), MeasureOr(d, "onset_s"), d.statistic, d.p_value,
          d.adopted ? "it stands against the drifts identified from decades" : "their misfit");
    case DecisionKind::kReferenceNoiseRaised:
      return ReferenceNoiseRaised(d);
    case DecisionKind::kNoiseRetuned:
      return NoiseRetuned(d);
    case DecisionKind::kQuantisationKept:
      return QuantisationKept(d);
    case DecisionKind::kStartExplainedByWarmUps:
      return absl::StrCat("the unit settles after power-up: model A failed only within its first ",
                          MeasureOr(d, "start_span_s"), " s, and with its warm-ups carried (", Names(d),
                          ") no failure remains there and nothing is found");
    case DecisionKind::kAPrioriModel:
      return APrioriModel(d);
    case DecisionKind::kUnitTypeSetAside:
      break;
  }
  return absl::StrFormat(
      "the run's Allan deviation on %s at τ %.3g s is %.3g times the unit type's nominal model at "
      "the family-wise confidence bound: further than the drift identification searches from it. "
      "The unit is analysed as one without a unit type: the a-priori model comes from its Allan "
      "deviation",
      Names(d), MeasureOr(d, "tau_s"), MeasureOr(d, "ratio"));
}

void DecisionLog::Record(Decision decision) {
  notes_.push_back(RenderNote(decision));
  decisions_.push_back(std::move(decision));
}

void DecisionLog::Note(std::string note) { notes_.push_back(std::move(note)); }

void DecisionLog::NoteEach(const std::vector<std::string>& notes) {
  notes_.insert(notes_.end(), notes.begin(), notes.end());
}

void DecisionLog::Append(const DecisionLog& later) {
  notes_.insert(notes_.end(), later.notes_.begin(), later.notes_.end());
  decisions_.insert(decisions_.end(), later.decisions_.begin(), later.decisions_.end());
}

}  // namespace insdiag::engine
