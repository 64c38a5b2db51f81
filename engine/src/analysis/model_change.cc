#include "analysis/model_change.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"

namespace insdiag::engine::pipeline {

// The identified parameters of a model that took structures of `found`:
// what the likelihood identified with each (a walk's K or a pair's σ₂, τ₂
// and period, and the drift σ fitted with it)
// replaces the earlier estimate of the same name.
std::vector<ParameterEstimate> WithTakenStructures(std::vector<ParameterEstimate> identified,
                                                   const ErrorModel& model, const Findings& found) {
  for (const StructureProposal& p : found.structures) {
    if (!p.fitted.has_value() || model.FindEffect(p.effect.term) < 0) continue;
    std::vector<ParameterEstimate> taken = p.fitted->parameters;
    taken.push_back(p.fitted->drift_sigma);
    for (const ParameterEstimate& e : taken) {
      std::erase_if(identified, [&](const ParameterEstimate& q) { return q.name == e.name; });
      identified.push_back(e);
    }
  }
  return identified;
}

namespace {

// Where a term placed in time is put: at the value the selector names (a
// fault's onset, a warm-up's time constant), else at the scan's; `candidate`
// is the scan's estimate of the term that states such a value, null if none.
struct ScannedPlacement {
  const EffectCandidate* candidate = nullptr;
  std::optional<double> value;
};

ScannedPlacement PlacementOf(const Findings& found, const EffectTerm& term,
                             std::optional<double> EffectCandidate::*placed_at, std::optional<double> named) {
  const auto c = std::find_if(found.candidates.begin(), found.candidates.end(), [&](const EffectCandidate& x) {
    return x.name == term.Name() && (x.*placed_at).has_value();
  });
  ScannedPlacement out;
  if (c != found.candidates.end()) out.candidate = &*c;
  out.value = named.has_value() ? named : out.candidate != nullptr ? out.candidate->*placed_at : std::nullopt;
  return out;
}

}  // namespace

// Model `base` plus `selectors`, with priors from what model A's scan and
// correlation processing found; anything not found gets the diffuse prior.
absl::StatusOr<ErrorModel> ExtendModel(const BenchRun& run, const ErrorModel& base,
                                       const std::vector<std::string>& selectors, const ScoreTestObserver* scan,
                                       const Findings& found, const AnalysisOptions& options) {
  ErrorModel model = base;
  std::vector<SelectedTerm> fallback;  // terms nothing found: the diffuse prior
  auto selected = ParseEffectSelectors(selectors);
  if (!selected.ok()) return selected.status();
  for (const SelectedTerm& named : *selected) {
    const EffectTerm& term = named.term;
    if (model.FindEffect(term) >= 0) continue;
    if (term.family->kind == EffectKind::kFault) {
      // At the onset named, else at the scan's: prior wide against the scan's estimate.
      const ScannedPlacement at = PlacementOf(found, term, &EffectCandidate::onset_s, named.onset_s);
      if (at.candidate == nullptr || !at.value.has_value()) {
        fallback.push_back({term.Name(), term, at.value, std::nullopt});
        continue;
      }
      model.effects.push_back(FaultEffectAt(term, *at.value, at.candidate->estimate, at.candidate->std_error, options));
      continue;
    }
    if (term.family->kind == EffectKind::kTransient) {
      // At the time constant named, else at the scan's, with its steady value beside it.
      const ScannedPlacement at = PlacementOf(found, term, &EffectCandidate::time_constant_s, named.time_constant_s);
      if (at.candidate == nullptr || !at.value.has_value()) {
        fallback.push_back({term.Name(), term, std::nullopt, at.value});
        continue;
      }
      AddWarmUp(term, *at.value, PriorSigmaAroundEstimate(at.candidate->estimate, at.candidate->std_error, options),
                model);
      continue;
    }
    auto structure =
        std::find_if(found.structures.begin(), found.structures.end(),
                     [&](const StructureProposal& p) { return p.effect.term == term; });
    if (structure != found.structures.end()) {
      model.effects.push_back(structure->effect);
      if (structure->fitted.has_value()) {
        DriftOf(model, structure->fitted->drift).sigma = structure->fitted->drift_sigma.value;
      }
      continue;
    }
    // A constant the scan estimated: prior wide against its estimate.
    bool placed = false;
    if (term.family->kind == EffectKind::kConstant && scan != nullptr) {
      ModelEffect e;
      e.term = term;
      const auto& cols = scan->columns();
      const Eigen::MatrixXd& I = scan->information();
      const Eigen::VectorXd& s = scan->score();
      placed = true;
      for (int p = 0; p < term.family->parameters_per_term; ++p) {
        auto it = std::find_if(cols.begin(), cols.end(), [&](const CandidateColumn& c) {
          return c.term == term && c.parameter == p;
        });
        const auto i = static_cast<Eigen::Index>(it - cols.begin());
        if (it == cols.end() || !(I(i, i) > 0.0)) {
          placed = false;
          break;
        }
        const double beta = s[i] / I(i, i);
        const double se = 1.0 / std::sqrt(I(i, i));
        e.prior_sigma[static_cast<size_t>(p)] = PriorSigmaAroundEstimate(beta, se, options);
      }
      if (placed) model.effects.push_back(e);
    }
    if (!placed) fallback.push_back({term.Name(), term, std::nullopt, std::nullopt});
  }
  if (auto st = AddEffects(run, fallback, options.filter.update_interval_s, options.diffuse_prior_scale, model); !st.ok()) {
    return st;
  }
  return model;
}

ModelComparison Compare(const ErrorModel& a, const ErrorModel& b, const AnalysisReport& ra, const AnalysisReport& rb,
                        double predicted_lr) {
  ModelComparison c;
  c.baseline_effects = a.EffectNames();
  for (const std::string& e : b.EffectNames()) {
    if (std::find(c.baseline_effects.begin(), c.baseline_effects.end(), e) == c.baseline_effects.end()) {
      c.added_effects.push_back(e);
    }
  }
  for (size_t i = 0; i < ra.channels.size() && i < rb.channels.size(); ++i) {
    c.channels.push_back({ra.channels[i].name, ra.channels[i], rb.channels[i]});
  }
  c.before = ra.fit;
  c.after = rb.fit;
  c.realized_lr = 2.0 * (rb.fit.log_likelihood - ra.fit.log_likelihood);
  c.predicted_lr = predicted_lr;
  return c;
}

// Whether `term_name` is one of the terms `selector` (a term or a family) stands for.
bool SelectorCovers(const std::string& selector, const std::string& term_name) {
  const auto terms = ParseEffectSelector(selector);
  return terms.ok() &&
         std::any_of(terms->begin(), terms->end(), [&](const EffectTerm& t) { return t.Name() == term_name; });
}

// Model A's score statistic for adding `added` jointly (the likelihood ratio it predicts).
double PredictedLikelihoodRatio(const ScoreTestObserver* scan, const std::vector<std::string>& added,
                                const Findings& found) {
  if (scan == nullptr) return 0.0;
  std::vector<Eigen::Index> idx;
  double structure_lr = 0.0;
  for (const std::string& name : added) {
    // A family stands for its terms.
    for (size_t i = 0; i < scan->columns().size(); ++i) {
      if (SelectorCovers(name, scan->columns()[i].term.Name())) idx.push_back(static_cast<Eigen::Index>(i));
    }
    for (const StructureProposal& p : found.structures) {
      if (p.candidate.name == name) structure_lr += p.candidate.statistic;
    }
    // A fault: the onset scan's likelihood ratio at its onset.
    for (const EffectCandidate& c : found.candidates) {
      if (IsFaultCandidate(c) && c.name == name.substr(0, name.find('@')))
        structure_lr += c.statistic;
    }
  }
  if (idx.empty()) return structure_lr;
  const auto n = static_cast<Eigen::Index>(idx.size());
  Eigen::VectorXd s(n);
  Eigen::MatrixXd I(n, n);
  for (Eigen::Index r = 0; r < n; ++r) {
    s[r] = scan->score()[idx[static_cast<size_t>(r)]];
    for (Eigen::Index c = 0; c < n; ++c) I(r, c) = scan->information()(idx[static_cast<size_t>(r)], idx[static_cast<size_t>(c)]);
  }
  return s.dot(I.completeOrthogonalDecomposition().solve(s)) + structure_lr;
}

namespace {

// What one discovery step added and how the model fits after it. The step's
// single value is the term's, or for a family its most significant term's
// (largest |estimate| / SE): a family has no one magnitude.
DiscoveryStep StepOf(int step, const EffectCandidate& top, const AnalysisReport& next_report) {
  DiscoveryStep d;
  d.step = step;
  d.effect = top.name;
  d.statistic = top.statistic;
  d.p_value = top.p_value_holm;
  d.unit = top.unit;
  d.estimate = top.estimate;
  d.std_error = top.std_error;
  // The added terms' estimates in the model after the step (one for a
  // term, one per axis or pair for a family).
  double largest_z = -1.0;
  for (const ParameterEstimate& e : next_report.identified) {
    if (e.method != EstimationMethod::kFilterState || !SelectorCovers(top.name, e.name)) continue;
    d.estimates.push_back(e);
    const double z = e.std_error > 0.0 ? std::abs(e.value) / e.std_error : 0.0;
    if (e.name == top.name || z > largest_z) {
      largest_z = e.name == top.name ? std::numeric_limits<double>::infinity() : z;
      d.estimate = e.value;
      d.std_error = e.std_error;
    }
  }
  d.fit = next_report.fit;
  d.channels = next_report.channels;
  return d;
}

}  // namespace

absl::StatusOr<Analysis> Discover(const RunContext& c, ScannedModelA a) {
  const AnalysisOptions& options = c.options;
  // Model A stays whole for the comparison; `latest` holds the last step's pass.
  std::optional<ModelPass> latest;
  auto current = [&]() -> const ModelPass& { return latest.has_value() ? *latest : a.pass; };
  Findings found = a.found;
  AnalysisReport report = a.report;
  std::vector<ParameterEstimate> identified = std::move(a.identified);
  for (int step = 1; step <= options.max_discovery_steps; ++step) {
    const EffectCandidate* top = NextDiscovery(found, options);
    if (top == nullptr) break;
    Progress(options, 0.7 + 0.3 * step / (options.max_discovery_steps + 1), "discovery: adding " + top->name);
    auto extended = ExtendModel(c.run, current().model, {top->name}, current().scan.get(), found, options);
    if (!extended.ok()) return extended.status();
    auto next = RunPass(c.run, c.epochs, *extended, c.samples, options, /*with_scan=*/true);
    if (!next.ok()) return next.status();
    const SettledStructures settled =
        !options.retest_settled_structures && AddsOnlyDeterministicEffects({top->name})
            ? SettledStructures{found.candidates, "the model before " + top->name + " was added"}
            : SettledStructures{};
    Findings next_found = FindMissingEffects(c, *next, options, &a.decisions, settled);
    identified = WithTakenStructures(std::move(identified), next->model, found);
    AnalysisReport next_report = ReportOf(c, *next, next_found, identified, a.decisions);
    report.discovery.push_back(StepOf(step, *top, next_report));
    next_report.discovery = report.discovery;
    latest = std::move(*next);
    found = std::move(next_found);
    report = std::move(next_report);
  }
  if (!report.discovery.empty()) {
    std::vector<std::string> added;
    for (const DiscoveryStep& d : report.discovery) added.push_back(d.effect);
    report.comparison =
        Compare(a.pass.model, current().model, a.report, report,
                PredictedLikelihoodRatio(a.pass.scan.get(), added, a.found));
  }
  Analysis out;
  out.report = std::move(report);
  out.model = current().model;
  out.base_report = std::move(a.report);
  if (options.keep_series) FillSeries(current(), out.series);
  return out;
}

absl::StatusOr<Analysis> AddAndCompare(const RunContext& c, const std::vector<std::string>& effects, ModelAForAdd a) {
  const AnalysisOptions& options = c.options;
  Progress(options, 0.8, "model with the added effects");
  auto extended = ExtendModel(c.run, a.model, effects, a.scan, a.found, options);
  if (!extended.ok()) return extended.status();
  auto b = RunPass(c.run, c.epochs, *extended, c.samples, options, /*with_scan=*/true);
  if (!b.ok()) return b.status();
  const SettledStructures settled = !options.retest_settled_structures && AddsOnlyDeterministicEffects(effects)
                                        ? SettledStructures{a.found.candidates, "model A, without the added effects"}
                                        : SettledStructures{};
  const Findings found_b = FindMissingEffects(c, *b, options, &a.decisions, settled);
  Analysis out;
  out.report = ReportOf(c, *b, found_b, WithTakenStructures(a.identified, b->model, a.found), a.decisions);
  std::vector<std::string> added;
  for (const std::string& e : b->model.EffectNames()) {
    if (a.model.FindEffect(*ParseEffectSelector(e)->begin()) < 0) added.push_back(e);
  }
  out.report.comparison =
      Compare(a.model, b->model, a.report, out.report, PredictedLikelihoodRatio(a.scan, added, a.found));
  out.model = b->model;
  out.base_report = std::move(a.report);
  if (options.keep_series) FillSeries(*b, out.series);
  return out;
}

namespace {

// A candidate of the report stands as a finding at family-wise `alpha`.
bool HasFinding(const AnalysisReport& report, double alpha) {
  return std::any_of(report.effect_candidates.begin(), report.effect_candidates.end(),
                     [&](const EffectCandidate& e) { return e.SignificantAt(alpha); });
}

// A failure interval of the report begins no later than `until_s`.
bool FailsBy(const AnalysisReport& report, double until_s) {
  return std::any_of(report.faults.begin(), report.faults.end(),
                     [&](const FaultInterval& f) { return f.start_s <= until_s; });
}

// A failure interval of the report begins after `after_s`.
bool FailsAfter(const AnalysisReport& report, double after_s) {
  return std::any_of(report.faults.begin(), report.faults.end(),
                     [&](const FaultInterval& f) { return f.start_s > after_s; });
}

// The model fails, only by `until_s`, and nothing else counts against it.
bool FailsOnlyBy(const AnalysisReport& report, double until_s, double alpha) {
  return report.verdict != Verdict::kGood && FailsBy(report, until_s) && !FailsAfter(report, until_s) &&
         !HasFinding(report, alpha);
}

// The listed warm-ups worth their two parameters by the BIC, as selectors at
// their time constants ("gyro_warm_up.x@516").
std::vector<std::string> WarmUpsLoweringTheBic(const AnalysisReport& report) {
  std::vector<std::string> out;
  for (const EffectCandidate& e : report.effect_candidates) {
    if (!e.time_constant_s.has_value() || !e.identifiable || !(e.predicted_delta_bic < 0.0)) continue;
    out.push_back(e.name + "@" + std::to_string(std::lround(*e.time_constant_s)));
  }
  return out;
}

}  // namespace

absl::StatusOr<std::optional<Analysis>> ExplainTheStartByWarmUps(const RunContext& c, const ScannedModelA& a) {
  const double alpha = c.options.finder.family_wise_alpha;
  const double start_span_s = c.options.onset_scan.min_side_s;
  const double start_span_end_s = c.run.samples.front().t_s + start_span_s;
  if (!FailsOnlyBy(a.report, start_span_end_s, alpha)) return std::nullopt;
  const std::vector<std::string> warm_ups = WarmUpsLoweringTheBic(a.report);
  if (warm_ups.empty()) return std::nullopt;
  auto b = AddAndCompare(c, warm_ups, a.ForAdd());
  if (!b.ok()) return b.status();
  const AnalysisReport& r = b->report;
  const bool better = static_cast<int>(r.verdict) < static_cast<int>(a.report.verdict);
  if (!better || FailsBy(r, start_span_end_s) || HasFinding(r, alpha)) return std::nullopt;
  Decision settles;
  settles.kind = DecisionKind::kStartExplainedByWarmUps;
  settles.subjects = warm_ups;
  settles.adopted = true;
  settles.rejected = {{"model A's failure", std::numeric_limits<double>::quiet_NaN()}};
  settles.measures = {{"start_span_s", start_span_s}};
  b->report.notes.push_back(RenderNote(settles));
  b->report.decisions.push_back(std::move(settles));
  return std::optional<Analysis>(*std::move(b));
}

}  // namespace insdiag::engine::pipeline
