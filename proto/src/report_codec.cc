#include "insdiag/api/report_codec.h"

#include <cmath>

#include "insdiag/engine/filter/observation.h"
#include "insdiag/engine/model/parameters.h"

namespace insdiag::api {
namespace {

v1::AnalysisReport::Verdict VerdictOf(engine::Verdict v) {
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

v1::IdentifiedParameter::Method MethodOf(const std::string& method) {
  if (method == "ACF") return v1::IdentifiedParameter::ACF;
  if (method == "ALLAN") return v1::IdentifiedParameter::ALLAN;
  if (method == "FILTER") return v1::IdentifiedParameter::FILTER;
  return v1::IdentifiedParameter::METHOD_UNSPECIFIED;
}

// JSON has no NaN or infinity: an unknown uncertainty is written as 0 and the
// field's comment says so.
double Finite(double v) { return std::isfinite(v) ? v : 0.0; }

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
  out->set_predicted_delta_aic(Finite(in.predicted_delta_aic));
  out->set_predicted_delta_bic(Finite(in.predicted_delta_bic));
  for (const auto& c : in.correlated_with) out->add_correlated_with(c);
  out->set_note(in.note);
  for (const auto& w : in.where) {
    v1::SegmentContribution* s = out->add_where();
    s->set_channel(w.channel);
    s->set_start_s(w.start_s);
    s->set_end_s(w.end_s);
    s->set_motion(w.motion);
    s->set_share(w.share);
  }
}

}  // namespace

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
  out.set_verdict(VerdictOf(r.verdict));
  *out.mutable_model() = ToProto(model);
  for (const engine::ChannelFit& c : r.channels) {
    v1::ChannelFit* f = out.add_channels();
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
  out.set_nis_mean(r.nis_mean);
  out.set_log_likelihood(r.log_likelihood);
  out.set_aic(r.aic);
  out.set_bic(r.bic);
  for (const engine::FaultInterval& f : r.faults) {
    v1::FaultInterval* fi = out.add_fault_intervals();
    fi->set_channel(f.channel);
    fi->set_start_s(f.start_s);
    fi->set_end_s(f.end_s);
    fi->set_kind(f.kind == engine::FaultKind::kOutlier ? v1::FaultInterval::OUTLIER : v1::FaultInterval::GRADUAL);
    fi->set_peak_statistic(Finite(f.peak_statistic));
  }
  for (const auto& c : r.effect_candidates) Fill(c, out.add_effect_candidates());
  for (const auto& c : r.family_candidates) Fill(c, out.add_family_candidates());
  for (const engine::ParameterEstimate& p : r.identified) {
    v1::IdentifiedParameter* ip = out.add_identified();
    ip->set_name(p.name);
    ip->set_value(p.value);
    ip->set_std_error(Finite(p.std_error));
    ip->set_method(MethodOf(p.method));
    ip->set_unit(p.unit);
    if (std::isfinite(p.a_priori)) ip->set_a_priori(p.a_priori);
  }
  out.set_update_count(r.scalar_updates);
  out.set_parameter_count(r.parameter_count);
  out.set_nis_band_low(r.nis_band_low);
  out.set_nis_band_high(r.nis_band_high);
  out.set_gamma2(r.gamma2);
  out.set_eta2(r.eta2);
  for (const auto& l : r.localisation) Fill(l, out.add_localisation());
  for (const auto& l : r.discrepancies) Fill(l, out.add_discrepancies());
  for (const auto& n : r.notes) out.add_notes(n);
  out.set_duration_s(r.duration_s);
  out.set_sample_count(static_cast<int64_t>(r.samples));
  out.set_sample_rate_hz(r.sample_rate_hz);
  out.set_update_interval_s(r.update_interval_s);
  return out;
}

v1::ResidualSeriesChunk ToProto(const engine::AnalysisSeries& s) {
  v1::ResidualSeriesChunk out;
  for (int c = 0; c < engine::kChannelCount; ++c) {
    for (size_t k = 0; k < s.time_s.size(); ++k) {
      const auto e = static_cast<Eigen::Index>(k);
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
