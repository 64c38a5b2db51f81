#include "sections.h"

#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>
#include <absl/strings/str_join.h>
#include <google/protobuf/util/time_util.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "insdiag/engine/finder/effect_finder.h"

namespace insdiag::testreport {
namespace {

using google::protobuf::util::TimeUtil;

// The two-sided 95 % quantile of the normal distribution: the interval
// printed beside each identified value is value ± kInterval95Z · SE.
constexpr double kInterval95Z = 1.959963984540054;

// The diagnosis's table lists the most probable modules and any other above
// 1 %: a filed document names the suspects, not every module with its
// evidence (the API's diagnosis keeps them all).
constexpr int kAlwaysListedModules = 3;
constexpr double kListedProbability = 0.01;

std::string Percent(double fraction) { return absl::StrFormat("%.1f %%", 100.0 * fraction); }

std::string Time(const google::protobuf::Timestamp& t) {
  return t.seconds() == 0 && t.nanos() == 0 ? "—" : TimeUtil::ToString(t);
}

std::string WithUnit(const std::string& value, const std::string& unit) {
  return unit.empty() ? value : absl::StrCat(value, " ", unit);
}

std::string EffectList(const v1::ErrorModel& model) {
  return model.effects().empty() ? "none (the base model)" : absl::StrJoin(model.effects(), ", ");
}

const v1::NominalParameter* NominalOf(const std::optional<v1::UnitType>& unit_type, const std::string& name) {
  if (!unit_type) return nullptr;
  for (const auto& p : unit_type->nominal()) {
    if (p.name() == name) return &p;
  }
  return nullptr;
}

// Whether an identified value is within the unit type's tolerance of its
// nominal value; nullopt where the unit type gives no tolerance for it.
std::optional<bool> WithinTolerance(const v1::IdentifiedParameter& p, const v1::NominalParameter* n) {
  if (n == nullptr || n->tolerance() <= 0) return std::nullopt;
  return std::abs(p.value() - n->value()) <= n->tolerance();
}

Tone ToneOf(v1::AnalysisReport::Verdict verdict) {
  switch (verdict) {
    case v1::AnalysisReport::GOOD: return Tone::kGood;
    case v1::AnalysisReport::OPERABLE: return Tone::kWarning;
    case v1::AnalysisReport::FAULTY: return Tone::kBad;
    default: return Tone::kNeutral;
  }
}

// Why the verdict is what it is, in the monitor's own terms (the rule is in
// engine/monitor/monitoring.h): failures first, then outliers, then the NIS.
std::string VerdictReason(const v1::AnalysisReport& r) {
  int gradual = 0, abrupt = 0, outliers = 0;
  for (const auto& f : r.fault_intervals()) {
    if (f.kind() == v1::FaultInterval::GRADUAL) ++gradual;
    if (f.kind() == v1::FaultInterval::ABRUPT) ++abrupt;
    if (f.kind() == v1::FaultInterval::OUTLIER) ++outliers;
  }
  std::vector<std::string> parts;
  if (gradual + abrupt == 0 && outliers == 0) parts.emplace_back("no fault interval on any channel");
  if (gradual + abrupt > 0) {
    parts.push_back(absl::StrCat("the model fails: ", gradual, " gradual and ", abrupt, " abrupt fault interval",
                                 gradual + abrupt == 1 ? "" : "s"));
  }
  if (outliers > 0) parts.push_back(absl::StrCat(outliers, " outlier interval", outliers == 1 ? "" : "s"));
  const bool nis_in = r.nis_mean() >= r.nis_band_low() && r.nis_mean() <= r.nis_band_high();
  parts.push_back(absl::StrCat("mean NIS ", Num(r.nis_mean()), nis_in ? " inside" : " outside", " its χ² band [",
                               Num(r.nis_band_low()), ", ", Num(r.nis_band_high()), "]"));
  return absl::StrCat(absl::StrJoin(parts, "; "), ".");
}

// Whether the run tells the parameter, in the table's words; "—" where it
// was not judged (methods other than FILTER, reports stored before the field).
std::string ObservabilityWords(v1::IdentifiedParameter::Observability verdict) {
  switch (verdict) {
    case v1::IdentifiedParameter::OBSERVABLE:
      return "observable";
    case v1::IdentifiedParameter::NOT_EXCITED:
      return "not excited";
    case v1::IdentifiedParameter::INSEPARABLE:
      return "inseparable";
    case v1::IdentifiedParameter::WEAKLY_DETERMINED:
      return "weakly determined";
    default:
      return "—";
  }
}

bool IsUnobservable(v1::IdentifiedParameter::Observability verdict) {
  return verdict == v1::IdentifiedParameter::NOT_EXCITED ||
         verdict == v1::IdentifiedParameter::INSEPARABLE ||
         verdict == v1::IdentifiedParameter::WEAKLY_DETERMINED;
}

}  // namespace

std::string Num(double v) {
  if (std::isnan(v)) return "—";
  if (std::isinf(v)) return v > 0 ? "∞" : "−∞";
  return absl::StrFormat("%.4g", v);
}

Section VerdictSection(const TestReportInput& input) {
  const v1::AnalysisReport& r = input.analysis.report();
  Section s{"Verdict", {}};
  const std::string verdict = v1::AnalysisReport::Verdict_Name(r.verdict());
  s.blocks.push_back(Callout{absl::StrCat("Verdict: ", verdict), VerdictReason(r), ToneOf(r.verdict())});
  // In plain words first: what is wrong, where, how sure, what to do.
  for (const auto& line : r.plain_words()) s.blocks.push_back(Paragraph{line});
  Fields f;
  f.items.push_back({"Verdict", verdict});
  f.items.push_back({"Effects in the model", EffectList(r.model())});
  for (const auto& l : r.localisation()) {
    f.items.push_back({"Failure localised to", absl::StrCat(l.state(), " at ", Num(l.time_s()), " s (", l.method(),
                                                            ", p = ", Num(l.p_value()), ")")});
  }
  std::vector<std::string> outside;
  for (const auto& p : r.identified()) {
    if (WithinTolerance(p, NominalOf(input.unit_type, p.name())) == false) outside.push_back(p.name());
  }
  if (input.unit_type) {
    f.items.push_back({"Outside the unit type's tolerance", outside.empty() ? "none" : absl::StrJoin(outside, ", ")});
  }
  if (input.diagnosis && !input.diagnosis->candidates().empty()) {
    const auto& top = input.diagnosis->candidates(0);
    f.items.push_back({"Most probable module", absl::StrCat(top.module(), " (", Percent(top.probability()), ")")});
  }
  s.blocks.push_back(std::move(f));
  return s;
}

Section UnitAndRunSection(const TestReportInput& input) {
  const v1::RunMetadata& m = input.run.metadata();
  const v1::Analysis& a = input.analysis;
  const v1::AnalysisReport& r = a.report();
  Section s{"Unit and run", {}};
  Fields unit;
  unit.items.push_back({"Unit serial", m.unit_serial()});
  unit.items.push_back({"Unit type", m.unit_type().empty() ? "not stated in the run" : m.unit_type()});
  unit.items.push_back({"Run", input.run.name()});
  unit.items.push_back({"Uploaded", Time(input.run.create_time())});
  unit.items.push_back({"Samples", absl::StrCat(input.run.sample_count(), " at ", Num(r.sample_rate_hz()), " Hz over ",
                                                Num(input.run.duration_s()), " s")});
  unit.items.push_back({"Samples' SHA-256", input.run.sha256()});
  if (m.has_site()) {
    unit.items.push_back({"Site", absl::StrCat(Num(m.site().latitude_deg()), "° N, ", Num(m.site().longitude_deg()),
                                               "° E, ", Num(m.site().height_m()), " m")});
  }
  for (const auto& e : m.extra()) unit.items.push_back({e.key(), e.value()});
  s.blocks.push_back(std::move(unit));
  Fields analysis;
  analysis.items.push_back({"Analysis", a.name()});
  analysis.items.push_back({"Created", Time(a.create_time())});
  analysis.items.push_back({"Finished", Time(a.update_time())});
  analysis.items.push_back({"Model", EffectList(r.model())});
  if (!a.base_analysis().empty()) analysis.items.push_back({"Model A from", a.base_analysis()});
  if (a.discover()) analysis.items.push_back({"Discovery", "the loop added significant effects until none was left"});
  analysis.items.push_back({"Filter updates", absl::StrCat(r.update_count(), " scalar updates every ",
                                                           Num(r.update_interval_s()), " s")});
  analysis.items.push_back({"Fit", absl::StrCat("log-likelihood ", Num(r.log_likelihood()), ", AIC ", Num(r.aic()),
                                                ", BIC ", Num(r.bic()), " (", r.parameter_count(), " parameters)")});
  s.blocks.push_back(std::move(analysis));
  return s;
}

Section TolerancesSection(const v1::AnalysisReport& r) {
  Section s{"Tolerances and where the model fails", {}};
  s.blocks.push_back(Paragraph{absl::StrCat(
      "The verdict is judged against the seed's tolerances: γ² = ", Num(r.gamma2()),
      " on each normalised residual β² = ν²/α², η² = ", Num(r.eta2()),
      " on the moving-window ratio F of actual to predicted residual variance, and the mean NIS inside its χ² band [",
      Num(r.nis_band_low()), ", ", Num(r.nis_band_high()),
      "]. FAULTY: a gradual or abrupt failure; OPERABLE: outliers only, or the mean NIS outside its band; "
      "GOOD otherwise. Fault intervals are reported where the statistics exceed their family-wise quantiles.")});
  Table channels{{"channel", "RMS", "fit", "mean NIS", "β² > γ²", "F > η²", "whiteness p"}, {}, {}, ""};
  for (const auto& c : r.channels()) {
    channels.rows.push_back({c.name(), WithUnit(Num(c.rms()), c.unit()), absl::StrFormat("%.1f %%", c.fit_percent()),
                             Num(c.nis_mean()), Percent(c.fraction_over_gamma2()), Percent(c.fraction_over_eta2()),
                             Num(c.whiteness_p_value())});
  }
  channels.caption = "Shares of updates with β² over γ² and of windows with F over η², per observation channel.";
  s.blocks.push_back(std::move(channels));
  if (r.bench_motion_size() > 0) {
    Table moved{{"sensor channel", "from [s]", "to [s]", "scatter over its quiet level [σ]"}, {}, {}, ""};
    for (const auto& m : r.bench_motion()) {
      moved.rows.push_back({m.channel(), Num(m.start_s()), Num(m.end_s()), Num(m.statistic())});
      moved.row_tones.push_back(Tone::kWarning);
    }
    moved.caption =
        "Where the bench moved while its reference says it was still: the unit's samples scatter far beyond their "
        "quiet level. The updates there test the bench, not the unit, and are not held against it.";
    s.blocks.push_back(std::move(moved));
  }
  if (r.fault_intervals().empty()) {
    s.blocks.push_back(Paragraph{"No fault interval: the model holds on every channel."});
    return s;
  }
  Table faults{{"channel", "from [s]", "to [s]", "kind", "peak statistic"}, {}, {}, ""};
  for (const auto& f : r.fault_intervals()) {
    faults.rows.push_back({f.channel(), Num(f.start_s()), Num(f.end_s()), v1::FaultInterval::Kind_Name(f.kind()),
                           Num(f.peak_statistic())});
    faults.row_tones.push_back(f.kind() == v1::FaultInterval::OUTLIER ? Tone::kWarning : Tone::kBad);
  }
  s.blocks.push_back(std::move(faults));
  return s;
}

Section ParametersSection(const v1::AnalysisReport& r, const std::optional<v1::UnitType>& unit_type) {
  Section s{"Identified parameters against nominal", {}};
  Table t{{"parameter", "value", "95 % interval", "nominal", "tolerance", "unit", "method",
           "against nominal", "observability"},
          {},
          {},
          ""};
  std::vector<std::string> unobservable;
  for (const auto& p : r.identified()) {
    const v1::NominalParameter* n = NominalOf(unit_type, p.name());
    std::string interval = "—";
    if (p.std_error() > 0) {
      interval = absl::StrCat("[", Num(p.value() - kInterval95Z * p.std_error()), ", ",
                              Num(p.value() + kInterval95Z * p.std_error()), "]");
    }
    std::string reference = "—";
    if (n != nullptr) {
      reference = Num(n->value());
    } else if (p.has_a_priori()) {
      reference = absl::StrCat(Num(p.a_priori()), " (a priori)");
    }
    const std::optional<bool> within = WithinTolerance(p, n);
    t.rows.push_back({p.name(), Num(p.value()), interval, reference,
                      n != nullptr ? Num(n->tolerance()) : "—", p.unit(),
                      v1::IdentifiedParameter::Method_Name(p.method()),
                      !within   ? "no tolerance"
                      : *within ? "within tolerance"
                                : "outside tolerance",
                      ObservabilityWords(p.observability())});
    const bool unobserved = IsUnobservable(p.observability());
    if (unobserved) {
      unobservable.push_back(absl::StrCat(p.name(), " (", ObservabilityWords(p.observability()),
                                          p.observability_note().empty() ? "" : ": ",
                                          p.observability_note(), ")"));
    }
    t.row_tones.push_back(within == false ? Tone::kBad
                          : unobserved    ? Tone::kWarning
                                          : Tone::kNeutral);
  }
  t.caption = absl::StrCat(
      "95 % interval: value ± ", Num(kInterval95Z), " standard errors. Nominal values and tolerances: ",
      unit_type ? absl::StrCat("unit type ", unit_type->display_name(), " (|value − nominal| ≤ tolerance is in spec)")
                : "the run names no unit type the knowledge base knows; a priori values are the model's start",
      ".");
  if (r.identified().empty()) {
    s.blocks.push_back(Paragraph{"The analysis identified no parameter."});
  } else {
    s.blocks.push_back(std::move(t));
  }
  // Which the run could not tell (docs/MULTI_POSITION.md): their values are the prior's and the
  // noise's.
  if (!unobservable.empty()) {
    s.blocks.push_back(
        Paragraph{absl::StrCat("Not observable in this run: ", absl::StrJoin(unobservable, "; "),
                               ". Their values say little about the unit.")});
  }
  return s;
}

Section EffectsSection(const v1::AnalysisReport& r) {
  Section s{"Effects found", {}};
  s.blocks.push_back(Paragraph{absl::StrCat("Effects in the model that produced this report: ", EffectList(r.model()),
                                            ".")});
  if (!r.discovery().empty()) {
    Table steps{{"step", "effect added", "estimate", "± SE", "unit", "Holm p before", "mean NIS after", "BIC after"},
                {}, {}, "The loop's path: each step added the most significant missing effect and ran again."};
    for (const auto& d : r.discovery()) {
      steps.rows.push_back({absl::StrCat(d.step()), d.effect(), Num(d.estimate()), Num(d.std_error()), d.unit(),
                            Num(d.p_value()), Num(d.nis_mean()), Num(d.bic())});
    }
    s.blocks.push_back(std::move(steps));
  }
  const double alpha = engine::FinderOptions{}.family_wise_alpha;
  Table missing{{"missing effect", "estimate", "± SE", "unit", "Holm p", "test", "onset [s]"}, {}, {}, ""};
  for (const auto& c : r.effect_candidates()) {
    if (c.not_tested() || c.p_value_holm() >= alpha) continue;
    missing.rows.push_back({c.name(), Num(c.estimate()), Num(c.std_error()), c.unit(), Num(c.p_value_holm()),
                            c.source(), c.has_onset_s() ? Num(c.onset_s()) : "—"});
  }
  if (missing.rows.empty()) {
    s.blocks.push_back(Paragraph{absl::StrCat("No catalogue effect missing from the model is significant at family-wise α = ",
                                              Num(alpha), " (Holm).")});
  } else {
    missing.caption = absl::StrCat("Catalogue effects the model lacks, significant at family-wise α = ", Num(alpha),
                                   " (Holm), most significant first.");
    s.blocks.push_back(std::move(missing));
  }
  if (!r.localisation().empty()) {
    Table where{{"sensor state", "at [s]", "method", "jump", "± SE", "p"}, {}, {}, "The sensor behind each failure."};
    for (const auto& l : r.localisation()) {
      where.rows.push_back({l.state(), Num(l.time_s()), l.method(), Num(l.jump()), Num(l.jump_std_error()),
                            Num(l.p_value())});
    }
    s.blocks.push_back(std::move(where));
  }
  return s;
}

Section DiagnosisSection(const std::optional<v1::Diagnosis>& diagnosis) {
  Section s{"Diagnosis", {}};
  if (!diagnosis) {
    s.blocks.push_back(Paragraph{"No diagnosis has been made of this analysis."});
    return s;
  }
  const v1::Diagnosis& d = *diagnosis;
  Fields f;
  f.items.push_back({"Diagnosis", d.name()});
  f.items.push_back({"Made", Time(d.create_time())});
  if (!d.failure_record().empty()) {
    f.items.push_back({"Resolved", absl::StrCat(d.resolved_module(), d.confirmed() ? " confirmed" : " rejected",
                                                " (", d.failure_record(), ")")});
  } else {
    f.items.push_back({"Resolved", "not yet"});
  }
  s.blocks.push_back(std::move(f));
  Table t{{"module", "failure mode", "probability", "evidence"}, {}, {}, "The unit's modules, most probable first."};
  int left_out = 0;
  for (int i = 0; i < d.candidates_size(); ++i) {
    const auto& c = d.candidates(i);
    if (i >= kAlwaysListedModules && c.probability() < kListedProbability) {
      ++left_out;
      continue;
    }
    t.rows.push_back({c.module(), c.failure_mode().empty() ? "—" : c.failure_mode(), Percent(c.probability()),
                      c.evidence().empty() ? "—" : absl::StrJoin(c.evidence(), "; ")});
  }
  if (left_out > 0) {
    absl::StrAppend(&t.caption, " ", left_out, " less probable module", left_out == 1 ? " is" : "s are",
                    " left out, each below ", Percent(kListedProbability), ".");
  }
  s.blocks.push_back(std::move(t));
  for (const auto& note : d.notes()) s.blocks.push_back(Paragraph{absl::StrCat("Note: ", note)});
  return s;
}

}  // namespace insdiag::testreport
