#include "insdiag/api/report_codec.h"

#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>

#include <cmath>
#include <limits>
#include <optional>
#include <string_view>

#include "insdiag/engine/candidate_source.h"
#include "insdiag/engine/filter/observation.h"
#include "insdiag/engine/model/parameter_key.h"
#include "insdiag/engine/model/parameters.h"

namespace insdiag::api {

v1::AnalysisReport::Verdict ToProto(engine::Verdict v) {
  switch (v) {
    case engine::Verdict::kGood:
      return v1::AnalysisReport::GOOD;
    case engine::Verdict::kOperable:
      return v1::AnalysisReport::OPERABLE;
    case engine::Verdict::kFaulty:
      return v1::AnalysisReport::FAULTY;
  }
  return v1::AnalysisReport::VERDICT_UNSPECIFIED;
}

std::optional<engine::Verdict> VerdictOf(v1::AnalysisReport::Verdict verdict) {
  switch (verdict) {
    case v1::AnalysisReport::GOOD: return engine::Verdict::kGood;
    case v1::AnalysisReport::OPERABLE: return engine::Verdict::kOperable;
    case v1::AnalysisReport::FAULTY: return engine::Verdict::kFaulty;
    default: return std::nullopt;
  }
}

v1::FaultInterval ToProto(const engine::FaultInterval& f) {
  v1::FaultInterval out;
  out.set_channel(f.channel);
  out.set_start_s(f.start_s);
  out.set_end_s(f.end_s);
  out.set_kind(f.kind == engine::FaultKind::kOutlier  ? v1::FaultInterval::OUTLIER
               : f.kind == engine::FaultKind::kAbrupt ? v1::FaultInterval::ABRUPT
                                                      : v1::FaultInterval::GRADUAL);
  out.set_peak_statistic(std::isfinite(f.peak_statistic) ? f.peak_statistic : 0.0);
  return out;
}

namespace {

// The API's enum names the methods as the engine does (MethodName).
v1::IdentifiedParameter::Method MethodOf(const std::optional<engine::EstimationMethod>& method) {
  v1::IdentifiedParameter::Method out = v1::IdentifiedParameter::METHOD_UNSPECIFIED;
  if (method.has_value()) v1::IdentifiedParameter::Method_Parse(std::string(engine::MethodName(*method)), &out);
  return out;
}

std::optional<engine::EstimationMethod> MethodOf(v1::IdentifiedParameter::Method method) {
  if (method == v1::IdentifiedParameter::METHOD_UNSPECIFIED) return std::nullopt;
  return engine::MethodNamed(v1::IdentifiedParameter::Method_Name(method));
}

// JSON has no NaN or infinity: an unknown uncertainty is written as 0 and the
// field's comment says so.
double Finite(double v) { return std::isfinite(v) ? v : 0.0; }

}  // namespace

Observability ObservabilityOf(const engine::ParameterEstimate& p) {
  // The filter's constants carry the prior and the correlation they are
  // judged by; other estimates carry neither.
  if (std::isnan(p.prior_std) && std::isnan(p.max_correlation)) return {};
  if (engine::ObservableByRun(p)) return {v1::IdentifiedParameter::OBSERVABLE, ""};
  // Why not, in the order ObservableByRun tests.
  if (std::abs(p.max_correlation) > engine::kSeparableCorrelation) {
    return {v1::IdentifiedParameter::INSEPARABLE,
            absl::StrFormat("only with %s (correlation %+.3f)", p.correlated_with, p.max_correlation)};
  }
  if (std::isinf(p.prior_std)) return {v1::IdentifiedParameter::NOT_EXCITED, "the test never excited it"};
  return {v1::IdentifiedParameter::WEAKLY_DETERMINED,
          absl::StrFormat("standard error %.2g of the prior's", p.std_error / p.prior_std)};
}

namespace {

void Fill(const engine::Localisation& in, v1::Localisation* out) {
  out->set_state(in.state);
  out->set_time_s(in.time_s);
  out->set_statistic(Finite(in.statistic));
  out->set_p_value(in.p_value);
  out->set_method(in.method);
  out->set_jump(in.jump);
  out->set_jump_std_error(in.jump_std_error);
}

void Fill(const engine::EffectCandidate& in, v1::EffectCandidate* out) {
  out->set_name(in.name);
  out->set_statistic(Finite(in.statistic));
  out->set_p_value(in.p_value);
  out->set_estimate(Finite(in.estimate));
  out->set_std_error(Finite(in.std_error));
  out->set_degrees_of_freedom(in.dof);
  out->set_unit(in.unit);
  out->set_family(in.family);
  out->set_source(in.source);
  out->set_p_value_holm(in.p_value_holm);
  out->set_identifiable(in.identifiable);
  out->set_not_tested(!in.tested);
  out->set_predicted_delta_aic(Finite(in.predicted_delta_aic));
  out->set_predicted_delta_bic(Finite(in.predicted_delta_bic));
  for (const auto& c : in.correlated_with) out->add_correlated_with(c);
  out->set_note(in.note);
  if (in.onset_s.has_value()) {
    out->set_onset_s(*in.onset_s);
    out->set_onset_std_s(in.onset_std_s);
    out->set_onset_low_s(in.onset_low_s);
    out->set_onset_high_s(in.onset_high_s);
    out->set_seen_in_raw_samples(in.seen_in_raw_samples);
  }
  if (in.time_constant_s.has_value()) out->set_time_constant_s(*in.time_constant_s);
  for (const auto& w : in.where) {
    v1::SegmentContribution* s = out->add_where();
    s->set_channel(w.channel);
    s->set_start_s(w.start_s);
    s->set_end_s(w.end_s);
    s->set_motion(w.motion);
    s->set_share(w.share);
  }
}

void Fill(const engine::ChannelFit& c, v1::ChannelFit* f) {
  f->set_name(c.name);
  f->set_rms(c.rms);
  f->set_fit_percent(c.fit_percent);
  f->set_nis_mean(c.nis_mean);
  f->set_whiteness_p_value(c.whiteness_p_value);
  f->set_unit(c.unit);
  f->set_sample_count(c.count);
  f->set_fraction_over_gamma2(c.fraction_over_gamma2);
  f->set_fraction_over_eta2(c.fraction_over_eta2);
}

void Fill(const engine::ParameterEstimate& p, v1::IdentifiedParameter* ip) {
  ip->set_name(p.name);
  ip->set_value(p.value);
  ip->set_std_error(Finite(p.std_error));
  ip->set_method(MethodOf(p.method));
  ip->set_unit(p.unit);
  if (std::isfinite(p.a_priori)) ip->set_a_priori(p.a_priori);
  const Observability o = ObservabilityOf(p);
  ip->set_observability(o.verdict);
  ip->set_observability_note(o.note);
  if (!p.jointly_with.empty() && std::isfinite(p.log_correlation)) {
    ip->set_jointly_with(p.jointly_with);
    ip->set_log_correlation(p.log_correlation);
  }
}

// Unit of a correlation fit's parameter for a drift of `sensor`.
std::string CorrelationParameterUnit(engine::Sensor sensor,
                                     engine::ident::CorrelationParameter parameter) {
  if (engine::ident::IsTimeS(parameter)) return "s";
  const engine::SensorUnits units = engine::UnitsOf(sensor);
  return std::string(parameter == engine::ident::CorrelationParameter::kDensity ? units.rate_walk
                                                                                : units.rate);
}

void Fill(const engine::DriftCorrelation& in, v1::CorrelationCurve* out) {
  const engine::ident::CorrelationAnalysis& a = in.analysis;
  out->set_state(in.state);
  out->set_dt_s(a.dt_s);
  for (double v : a.acf) out->add_acf(v);
  for (double v : a.acf_band) out->add_band(Finite(v));
  for (double v : a.error_acf) out->add_error_acf(v);
  for (const engine::ident::FamilyFit& f : a.fits) {
    if (!f.usable) continue;
    v1::FamilyCurve* fc = out->add_fits();
    fc->set_family(engine::ident::CorrelationFamilyName(f.family));
    for (double v : f.expected) fc->add_expected(v);
    fc->set_aic(Finite(f.aic));
    fc->set_bic(Finite(f.bic));
    fc->set_lr_statistic(Finite(f.lr_statistic));
    fc->set_lr_p_value(f.lr_p_value);
    for (const engine::ident::FittedParameter& p : f.parameters) {
      v1::IdentifiedParameter* ip = fc->add_parameters();
      ip->set_name(in.state + "." + std::string(p.Name()));
      ip->set_value(p.value);
      ip->set_std_error(Finite(p.std_error));
      ip->set_method(v1::IdentifiedParameter::ACF);
      ip->set_unit(CorrelationParameterUnit(in.sensor, p.id));
    }
  }
  out->set_best_family(engine::ident::CorrelationFamilyName(a.best));
  out->set_resolved(a.resolved);
}

void Fill(const engine::ident::AllanChannel& ch, const std::vector<engine::ParameterEstimate>& terms,
          v1::AllanCurve* out) {
  out->set_channel(ch.name);
  out->set_unit(ch.unit);
  for (const engine::ident::AllanPoint& p : ch.curve) {
    out->add_tau_s(p.tau_s);
    out->add_deviation(p.adev);
    out->add_deviation_low(p.ci_low);
    out->add_deviation_high(p.ci_high);
    out->add_fitted(Finite(p.fitted_adev));
  }
  for (const engine::ident::RateJump& j : ch.jumps) out->add_jump_times_s(j.time_s);
  // The channel's terms: "{gyro|acc}_<term>.<axis>[.<parameter>]" on its one axis.
  for (const engine::ParameterEstimate& t : terms) {
    const std::optional<engine::ParameterKey> key = engine::ParseParameterKey(t.name);
    const bool this_channel =
        key && key->sensor == ch.sensor && key->axes == engine::AxisName(ch.axis);
    if (this_channel) Fill(t, out->add_terms());
  }
}

// The fit's four figures into a message that carries them as its own
// fields (a report, a discovery step).
template <typename Message>
void FillFit(const engine::FitMetrics& fit, Message* out) {
  out->set_nis_mean(fit.nis_mean);
  out->set_log_likelihood(fit.log_likelihood);
  out->set_aic(fit.aic);
  out->set_bic(fit.bic);
}

void Fill(const engine::ModelComparison& in, v1::ModelComparison* out) {
  for (const auto& e : in.baseline_effects) out->add_baseline_effects(e);
  for (const auto& e : in.added_effects) out->add_added_effects(e);
  for (const engine::ChannelComparison& c : in.channels) {
    v1::ChannelComparison* cc = out->add_channels();
    cc->set_name(c.name);
    cc->set_rms_before(c.before.rms);
    cc->set_rms_after(c.after.rms);
    cc->set_nis_mean_before(c.before.nis_mean);
    cc->set_nis_mean_after(c.after.nis_mean);
    cc->set_whiteness_p_value_before(c.before.whiteness_p_value);
    cc->set_whiteness_p_value_after(c.after.whiteness_p_value);
    cc->set_fit_percent_before(c.before.fit_percent);
    cc->set_fit_percent_after(c.after.fit_percent);
  }
  out->set_nis_mean_before(in.before.nis_mean);
  out->set_nis_mean_after(in.after.nis_mean);
  out->set_log_likelihood_before(in.before.log_likelihood);
  out->set_log_likelihood_after(in.after.log_likelihood);
  out->set_aic_before(in.before.aic);
  out->set_aic_after(in.after.aic);
  out->set_bic_before(in.before.bic);
  out->set_bic_after(in.after.bic);
  out->set_realized_lr(in.realized_lr);
  out->set_predicted_lr(Finite(in.predicted_lr));
}

void Fill(const engine::DiscoveryStep& in, v1::DiscoveryStep* out) {
  out->set_step(in.step);
  out->set_effect(in.effect);
  out->set_estimate(Finite(in.estimate));
  out->set_std_error(Finite(in.std_error));
  out->set_unit(in.unit);
  out->set_statistic(Finite(in.statistic));
  out->set_p_value(in.p_value);
  FillFit(in.fit, out);
  for (const engine::ChannelFit& c : in.channels) Fill(c, out->add_channels());
  for (const engine::ParameterEstimate& e : in.estimates) Fill(e, out->add_estimates());
}

// The inverse of Fill for a candidate: 0 in the report stands for a
// standard error never computed (JSON has no infinity).
engine::EffectCandidate CandidateOf(const v1::EffectCandidate& in) {
  engine::EffectCandidate out;
  out.name = in.name();
  out.family = in.family();
  out.source = in.source();
  out.statistic = in.statistic();
  out.dof = in.degrees_of_freedom();
  out.p_value = in.p_value();
  out.p_value_holm = in.p_value_holm();
  out.estimate = in.estimate();
  out.std_error = in.std_error() > 0.0 ? in.std_error() : std::numeric_limits<double>::infinity();
  out.unit = in.unit();
  out.identifiable = in.identifiable();
  out.tested = !in.not_tested();
  out.predicted_delta_aic = in.predicted_delta_aic();
  out.predicted_delta_bic = in.predicted_delta_bic();
  out.correlated_with.assign(in.correlated_with().begin(), in.correlated_with().end());
  for (const v1::SegmentContribution& w : in.where()) {
    out.where.push_back({w.channel(), w.start_s(), w.end_s(), w.motion(), w.share()});
  }
  out.note = in.note();
  if (in.has_onset_s()) {
    out.onset_s = in.onset_s();
    out.onset_std_s = in.onset_std_s();
    out.onset_low_s = in.onset_low_s();
    out.onset_high_s = in.onset_high_s();
    out.seen_in_raw_samples = in.seen_in_raw_samples();
  }
  if (in.has_time_constant_s()) out.time_constant_s = in.time_constant_s();
  return out;
}

v1::Decision::Kind ToProto(engine::DecisionKind kind) {
  switch (kind) {
    case engine::DecisionKind::kDriftsIdentified:
      return v1::Decision::DRIFTS_IDENTIFIED;
    case engine::DecisionKind::kDriftsNotIdentifiable:
      return v1::Decision::DRIFTS_NOT_IDENTIFIABLE;
    case engine::DecisionKind::kDriftErrorsWidened:
      return v1::Decision::DRIFT_ERRORS_WIDENED;
    case engine::DecisionKind::kDriftsOverCandidate:
      return v1::Decision::DRIFTS_OVER_CANDIDATE;
    case engine::DecisionKind::kFaultAgainstDrifts:
      return v1::Decision::FAULT_AGAINST_DRIFTS;
    case engine::DecisionKind::kReferenceNoiseRaised:
      return v1::Decision::REFERENCE_NOISE_RAISED;
    case engine::DecisionKind::kNoiseRetuned:
      return v1::Decision::NOISE_RETUNED;
    case engine::DecisionKind::kUnitTypeSetAside:
      return v1::Decision::UNIT_TYPE_SET_ASIDE;
    case engine::DecisionKind::kQuantisationKept:
      return v1::Decision::QUANTISATION_KEPT;
    case engine::DecisionKind::kAPrioriModel:
      return v1::Decision::A_PRIORI_MODEL;
    case engine::DecisionKind::kStartExplainedByWarmUps:
      break;
  }
  return v1::Decision::START_EXPLAINED_BY_WARM_UPS;
}

void Fill(const engine::Decision& d, v1::Decision* out) {
  out->set_kind(ToProto(d.kind));
  for (const std::string& s : d.subjects) out->add_subjects(s);
  out->set_scope(d.scope);
  if (std::isfinite(d.statistic)) out->set_statistic(d.statistic);
  out->set_degrees_of_freedom(d.degrees_of_freedom);
  if (std::isfinite(d.level)) out->set_level(d.level);
  if (std::isfinite(d.p_value)) out->set_p_value(d.p_value);
  out->set_adopted(d.adopted);
  for (const engine::WeighedAlternative& a : d.rejected) {
    v1::Decision::Alternative* alternative = out->add_rejected();
    alternative->set_name(a.name);
    if (std::isfinite(a.statistic)) alternative->set_statistic(a.statistic);
  }
  for (const auto& [name, value] : d.measures) {
    v1::Decision::Measure* m = out->add_measures();
    m->set_name(name);
    m->set_value(value);
  }
  for (const std::string& q : d.qualifiers) out->add_qualifiers(q);
  out->set_note(engine::RenderNote(d));
}

}  // namespace

absl::StatusOr<engine::IdentifiedModel> IdentifiedModelOf(const v1::AnalysisReport& report) {
  engine::IdentifiedModel out;
  // Every effect states at least one parameter (engine/model/parameters.h), so
  // the parameters alone give the effects back, in the model's order.
  for (int i = 0; i < report.model().parameters_size(); ++i) {
    const v1::ModelParameter& p = report.model().parameters(i);
    if (auto set = engine::SetParameter(p.name(), p.value(), out.model); !set.ok()) {
      return absl::InvalidArgumentError(
          absl::StrCat("report.model.parameters[", i, "] (", p.name(), "): ", set.message()));
    }
  }
  for (const v1::IdentifiedParameter& p : report.identified()) {
    engine::ParameterEstimate e;
    e.name = p.name();
    e.value = p.value();
    // 0 stands for "none" in the report (JSON has no NaN).
    if (p.std_error() > 0.0) e.std_error = p.std_error();
    e.method = MethodOf(p.method());
    e.unit = p.unit();
    if (p.has_a_priori()) e.a_priori = p.a_priori();
    if (p.has_log_correlation()) {
      e.jointly_with = p.jointly_with();
      e.log_correlation = p.log_correlation();
    }
    out.identified.push_back(std::move(e));
  }
  for (const v1::EffectCandidate& c : report.effect_candidates()) {
    if (engine::CandidateSourceNamed(c.source()) == engine::CandidateSource::kLikelihood)
      out.structure_outcomes.push_back(CandidateOf(c));
  }
  return out;
}

v1::ErrorModel ToProto(const engine::ErrorModel& model) {
  v1::ErrorModel out;
  for (const std::string& e : model.EffectNames()) out.add_effects(e);
  for (const engine::NamedParameter& p : engine::ParametersOf(model)) {
    v1::ModelParameter* mp = out.add_parameters();
    mp->set_name(p.name);
    mp->set_value(p.value);
    mp->set_unit(p.unit);
  }
  return out;
}

v1::AnalysisReport ToProto(const engine::AnalysisReport& r, const engine::ErrorModel& model) {
  v1::AnalysisReport out;
  out.set_verdict(ToProto(r.verdict));
  *out.mutable_model() = ToProto(model);
  for (const engine::ChannelFit& c : r.channels) Fill(c, out.add_channels());
  FillFit(r.fit, &out);
  for (const engine::FaultInterval& f : r.faults) *out.add_fault_intervals() = ToProto(f);
  for (const engine::BenchMotion& m : r.bench_motion) {
    v1::BenchMotion* b = out.add_bench_motion();
    b->set_start_s(m.start_s);
    b->set_end_s(m.end_s);
    b->set_channel(std::string(engine::kSensorChannelNames[static_cast<size_t>(m.sensor_channel)]));
    b->set_statistic(m.statistic);
  }
  for (const auto& c : r.effect_candidates) Fill(c, out.add_effect_candidates());
  for (const auto& c : r.family_candidates) Fill(c, out.add_family_candidates());
  for (const engine::ParameterEstimate& p : r.identified) Fill(p, out.add_identified());
  out.set_update_count(r.scalar_updates);
  out.set_parameter_count(r.parameter_count);
  out.set_nis_band_low(r.nis_band_low);
  out.set_nis_band_high(r.nis_band_high);
  out.set_gamma2(r.gamma2);
  out.set_eta2(r.eta2);
  for (const auto& l : r.localisation) Fill(l, out.add_localisation());
  for (const auto& l : r.discrepancies) Fill(l, out.add_discrepancies());
  for (const auto& n : r.notes) out.add_notes(n);
  for (const auto& line : r.plain_words) out.add_plain_words(line);
  for (const engine::Decision& d : r.decisions) Fill(d, out.add_decisions());
  out.set_duration_s(r.duration_s);
  out.set_sample_count(static_cast<int64_t>(r.samples));
  out.set_sample_rate_hz(r.sample_rate_hz);
  out.set_update_interval_s(r.update_interval_s);
  for (const engine::DriftCorrelation& d : r.correlation) Fill(d, out.add_correlation());
  if (r.allan.has_value()) {
    const std::vector<engine::ParameterEstimate> terms = engine::ident::AllanParameterEstimates(*r.allan);
    for (const engine::ident::AllanChannel& ch : r.allan->channels) Fill(ch, terms, out.add_allan());
  }
  if (r.comparison.has_value()) Fill(*r.comparison, out.mutable_comparison());
  for (const engine::DiscoveryStep& d : r.discovery) Fill(d, out.add_discovery());
  return out;
}

v1::ResidualSeriesChunk ToProto(const engine::AnalysisSeries& s) {
  v1::ResidualSeriesChunk out;
  for (int c = 0; c < engine::kChannelCount; ++c) {
    for (size_t k = 0; k < s.time_s.size(); ++k) {
      const auto e = static_cast<Eigen::Index>(k);
      if (!(s.sigma(e, c) > 0.0)) continue;  // not observed at this epoch (the attitude while the table turns)
      v1::ResidualPoint* p = out.add_points();
      p->set_channel(std::string(engine::kChannelNames[static_cast<size_t>(c)]));
      p->set_t(s.time_s[k]);
      p->set_measured(s.measured(e, c));
      p->set_predicted(s.predicted(e, c));
      p->set_residual(s.residual(e, c));
      p->set_sigma3(3.0 * s.sigma(e, c));
    }
  }
  return out;
}

}  // namespace insdiag::api
