// What a stage of the analysis decided, as data. Each decision names its
// kind, the terms it is about, the statistic it weighed against which level,
// whether the model took it, and the alternatives it weighed and rejected;
// the report's prose note is rendered from it (RenderNote). The report
// carries the records (AnalysisReport::decisions, the proto's `decisions`)
// beside the notes, so the page, the diagnosis and the tests act on what
// the engine decided rather than on its prose.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace insdiag::engine {

enum class DecisionKind {
  // The selected drifts' σ (and τ) by the innovations' likelihood, taken
  // or kept at the model's values by 2Δℓ against χ² at the level.
  kDriftsIdentified,
  // Drifts whose likelihood is flat with the run's motion: the model keeps
  // their values.
  kDriftsNotIdentifiable,
  // Drift standard errors widened to their likelihood ratio against the
  // a-priori values.
  kDriftErrorsWidened,
  // The a-priori model's misfit explained by its drifts rather than by the
  // best missing-effect candidate, by ΔBIC (the candidate is the rejected
  // alternative).
  kDriftsOverCandidate,
  // A bias step or ramp tested against the drifts identified beside it:
  // adopted where it stands, rejected as their misfit.
  kFaultAgainstDrifts,
  // The bench's reference noise raised by likelihood: the innovations
  // exceed what its stated accuracy predicts.
  kReferenceNoiseRaised,
  // Noise terms an Allan fit set from bounds or seeded, scaled together by
  // likelihood (measures "scale" and "log_std_error").
  kNoiseRetuned,
  // The unit type's nominal model set aside for the run's own Allan fit:
  // the run's Allan deviation on a channel (the subject) departs from it
  // beyond what the drift identification searches (measures "tau_s",
  // "ratio"; the unit type is the rejected alternative).
  kUnitTypeSetAside,
  // An Allan fit's accelerometer quantisation (subjects: its parameters,
  // each a measure in m/s) kept where the innovations' likelihood prefers
  // it, by 2Δℓ with and without it; qualifier "after_the_drifts" or
  // "before_the_drifts" says which drifts it was weighed beside.
  kQuantisationKept,
  // Model A failed only within the run's first `start_span_s` and the
  // warm-ups (subjects) carried in model B leave no failure there: the
  // unit settling after power-up, not a fault.
  kStartExplainedByWarmUps,
  // Where model A's a-priori values came from, as one qualifier:
  // "datasheet" (the unit's own specification), "nominal" (the nominal
  // model given for it, its unit type's: a class prior), "allan_fit" (the run's own Allan
  // deviation; "no_specification" where the run had neither of the
  // others) or "earlier_analysis" (the model an earlier analysis of the run
  // identified, not identified again).
  kAPrioriModel,
};

// An alternative a decision weighed, with its statistic in the decision's terms.
struct WeighedAlternative {
  std::string name;
  double statistic = std::numeric_limits<double>::quiet_NaN();
};

struct Decision {
  DecisionKind kind = DecisionKind::kDriftsIdentified;
  std::vector<std::string> subjects;  // the terms or parameters it is about
  std::string scope;                  // the group they form, where they form one ("gyro white")
  double statistic = std::numeric_limits<double>::quiet_NaN();  // 2Δℓ, or ΔBIC
  int degrees_of_freedom = 0;                                   // of a χ² test; 0 where none
  double level = std::numeric_limits<double>::quiet_NaN();      // the test's family-wise α
  double p_value = std::numeric_limits<double>::quiet_NaN();
  bool adopted = false;  // whether the model took what was tested
  std::vector<WeighedAlternative> rejected;
  // Named quantities of the decision, in the units their names give
  // ("onset_s", "iterations", "filter_passes").
  std::vector<std::pair<std::string, double>> measures;
  // The reason in the decision's own terms where its kind has more than one
  // ("allan_fit_prior": the model's values were an Allan fit's, no
  // specification; "placeholders": taken on that alone; "not_converged").
  std::vector<std::string> qualifiers;

  std::optional<double> Measure(std::string_view name) const;
  bool Qualified(std::string_view qualifier) const;
};

// The prose note of a decision, as the report's `notes` carry it.
std::string RenderNote(const Decision& decision);

// The notes and decisions of an analysis in the order they were made: each
// decision adds its rendered note; prose without a record of its own (a
// fallback taken, a stage that could not run) is a note alone.
class DecisionLog {
 public:
  void Record(Decision decision);
  void Note(std::string note);
  // Notes a lower layer wrote as prose (ident/), each as a note.
  void NoteEach(const std::vector<std::string>& notes);
  // Another log's notes and decisions after this one's.
  void Append(const DecisionLog& later);

  const std::vector<std::string>& notes() const { return notes_; }
  const std::vector<Decision>& decisions() const { return decisions_; }
  bool empty() const { return notes_.empty(); }

 private:
  std::vector<std::string> notes_;
  std::vector<Decision> decisions_;
};

}  // namespace insdiag::engine
