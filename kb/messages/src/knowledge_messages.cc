#include "insdiag/kb/knowledge_messages.h"

#include <absl/strings/str_cat.h>

#include <optional>

#include "insdiag/api/report_codec.h"
#include "insdiag/api/time_codec.h"

namespace insdiag::kb {
namespace {

Direction DirectionOf(v1::Signature::Direction direction) {
  switch (direction) {
    case v1::Signature::UP: return Direction::kUp;
    case v1::Signature::DOWN: return Direction::kDown;
    default: return Direction::kEither;
  }
}

v1::Signature::Direction ToProto(Direction direction) {
  switch (direction) {
    case Direction::kUp: return v1::Signature::UP;
    case Direction::kDown: return v1::Signature::DOWN;
    case Direction::kEither: return v1::Signature::EITHER;
  }
  return v1::Signature::EITHER;
}

}  // namespace

UnitType UnitTypeOf(const v1::UnitType& message) {
  UnitType out;
  out.name = message.name();
  out.display_name = message.display_name();
  out.description = message.description();
  for (const auto& p : message.nominal()) {
    NominalParameter n;
    n.name = p.name();
    n.value = p.value();
    n.tolerance = p.tolerance();
    n.unit = p.unit();
    out.nominal.push_back(std::move(n));
  }
  return out;
}

v1::UnitType ToProto(const UnitType& unit_type) {
  v1::UnitType out;
  out.set_name(unit_type.name);
  out.set_display_name(unit_type.display_name);
  out.set_description(unit_type.description);
  for (const NominalParameter& n : unit_type.nominal) {
    v1::NominalParameter* p = out.add_nominal();
    p->set_name(n.name);
    p->set_value(n.value);
    p->set_tolerance(n.tolerance);
    p->set_unit(n.unit);
  }
  return out;
}

Signature SignatureOf(const v1::Signature& message) {
  Signature out;
  out.parameter = message.parameter();
  out.direction = DirectionOf(message.direction());
  out.change = message.change();
  out.spread = message.spread();
  out.scale = ScaleNamed(message.scale()).value_or(Scale::kTolerance);
  out.common = message.common();
  out.fraction = message.fraction();
  out.expert_change = message.expert_change();
  out.expert_spread = message.expert_spread();
  out.confirmed_cases = message.confirmed_cases();
  return out;
}

v1::Signature ToProto(const Signature& signature) {
  v1::Signature out;
  out.set_parameter(signature.parameter);
  out.set_direction(ToProto(signature.direction));
  out.set_change(signature.change);
  out.set_spread(signature.spread);
  out.set_scale(ScaleName(signature.scale));
  out.set_common(signature.common);
  out.set_fraction(signature.fraction);
  out.set_expert_change(signature.expert_change);
  out.set_expert_spread(signature.expert_spread);
  out.set_confirmed_cases(signature.confirmed_cases);
  return out;
}

FailureMode FailureModeOf(const v1::FailureMode& message) {
  FailureMode out;
  out.name = message.name();
  out.module_role = message.module_role();
  out.description = message.description();
  for (const auto& s : message.signature()) out.signature.push_back(SignatureOf(s));
  out.display_name = message.display_name();
  out.unit_type = message.unit_type();
  out.expert_rate_per_million_hours = message.expert_rate_per_million_hours();
  out.rate_per_million_hours = message.rate_per_million_hours();
  out.confirmed_failures = message.confirmed_failures();
  out.weibull_shape = message.weibull_shape();
  out.weibull_scale_hours = message.weibull_scale_hours();
  return out;
}

v1::FailureMode ToProto(const FailureMode& mode) {
  v1::FailureMode out;
  out.set_name(mode.name);
  out.set_module_role(mode.module_role);
  out.set_description(mode.description);
  for (const Signature& s : mode.signature) *out.add_signature() = ToProto(s);
  out.set_display_name(mode.display_name);
  out.set_unit_type(mode.unit_type);
  out.set_expert_rate_per_million_hours(mode.expert_rate_per_million_hours);
  out.set_rate_per_million_hours(mode.rate_per_million_hours);
  out.set_confirmed_failures(mode.confirmed_failures);
  out.set_weibull_shape(mode.weibull_shape);
  out.set_weibull_scale_hours(mode.weibull_scale_hours);
  return out;
}

DiagnosisSettings SettingsOf(const v1::DiagnosisSettings& message) {
  DiagnosisSettings out;
  out.healthy_tolerance_sd = message.healthy_tolerance_sd();
  out.healthy_log_ratio_fraction = message.healthy_log_ratio_fraction();
  out.healthy_z_sd = message.healthy_z_sd();
  out.contamination = message.contamination();
  out.broad_log_ratio = message.broad_log_ratio();
  out.broad_tolerance = message.broad_tolerance();
  out.broad_z = message.broad_z();
  out.unknown_prior = message.unknown_prior();
  out.minimum_exposure_hours = message.minimum_exposure_hours();
  out.expert_pseudo_hours = message.expert_pseudo_hours();
  out.expert_signature_weight = message.expert_signature_weight();
  out.significance_level = message.significance_level();
  out.incidental_contamination = message.incidental_contamination();
  out.trend_z_change = message.trend_z_change();
  out.trend_z_spread = message.trend_z_spread();
  out.present_score_octaves = message.present_score_octaves();
  return out;
}

v1::Diagnosis ToProto(const Diagnosis& diagnosis) {
  v1::Diagnosis out;
  out.set_analysis(diagnosis.analysis);
  out.set_unit(diagnosis.unit);
  for (const Candidate& c : diagnosis.candidates) {
    v1::Candidate* candidate = out.add_candidates();
    candidate->set_module(c.module);
    candidate->set_failure_mode(c.failure_mode);
    candidate->set_probability(c.probability);
    for (const std::string& line : c.evidence) candidate->add_evidence(line);
  }
  for (const Hypothesis& h : diagnosis.hypotheses) {
    v1::Hypothesis* hypothesis = out.add_hypotheses();
    hypothesis->set_failure_mode(h.failure_mode);
    hypothesis->set_module(h.module);
    hypothesis->set_prior(h.prior);
    hypothesis->set_log_likelihood(h.log_likelihood);
    hypothesis->set_probability(h.probability);
  }
  for (const std::string& note : diagnosis.notes) out.add_notes(note);
  for (const EvidenceItem& e : diagnosis.evidence) {
    v1::EvidenceItem* item = out.add_evidence();
    item->set_name(e.name);
    item->set_scale(ScaleName(e.scale));
    item->set_value(e.value);
    item->set_measurement_sd(e.measurement_sd);
    item->set_healthy_sd(e.healthy_sd);
    item->set_significant(e.significant);
  }
  return out;
}

std::string EncodeDiagnosis(const Diagnosis& diagnosis, const std::string& name, absl::Time create_time) {
  v1::Diagnosis message = ToProto(diagnosis);
  message.set_name(name);
  *message.mutable_create_time() = api::TimestampOf(create_time);
  std::string bytes;
  message.SerializeToString(&bytes);
  return bytes;
}

absl::StatusOr<v1::Diagnosis> DecodeDiagnosis(const StoredDiagnosis& stored) {
  v1::Diagnosis message;
  if (!message.ParseFromString(stored.encoded)) {
    return absl::InternalError(absl::StrCat(stored.name, ": the stored diagnosis cannot be read"));
  }
  if (!stored.failure_record.empty()) {
    message.set_failure_record(stored.failure_record);
    message.set_confirmed(stored.confirmed);
    message.set_resolved_module(stored.resolved_module);
  }
  return message;
}

ReportFindings FindingsOf(const v1::AnalysisReport& report) {
  ReportFindings out;
  out.verdict = api::VerdictOf(report.verdict());
  for (const auto& p : report.identified()) {
    IdentifiedFinding f;
    f.name = p.name();
    f.value = p.value();
    f.std_error = p.std_error();
    f.unit = p.unit();
    f.method = v1::IdentifiedParameter::Method_Name(p.method());
    f.jointly_with = p.jointly_with();
    if (p.has_log_correlation()) f.log_correlation = p.log_correlation();
    out.identified.push_back(std::move(f));
  }
  for (const auto& c : report.effect_candidates()) {
    CandidateFinding f;
    f.name = c.name();
    f.estimate = c.estimate();
    f.std_error = c.std_error();
    f.unit = c.unit();
    f.statistic = c.statistic();
    f.degrees_of_freedom = c.degrees_of_freedom();
    f.p_value = c.p_value();
    f.p_value_holm = c.p_value_holm();
    f.source = c.source();
    f.identifiable = c.identifiable();
    f.not_tested = c.not_tested();
    if (c.has_onset_s()) f.onset_s = c.onset_s();
    f.onset_std_s = c.onset_std_s();
    out.candidates.push_back(std::move(f));
  }
  out.model_effects.assign(report.model().effects().begin(), report.model().effects().end());
  for (const v1::Decision& d : report.decisions()) {
    if (d.kind() != v1::Decision::UNIT_TYPE_SET_ASIDE || d.subjects().empty()) continue;
    UnitTypeSetAside aside;
    aside.channel = d.subjects(0);
    for (const auto& m : d.measures()) {
      if (m.name() == "tau_s") aside.tau_s = m.value();
      if (m.name() == "ratio") aside.ratio = m.value();
    }
    out.unit_type_set_aside = std::move(aside);
  }
  for (const auto& s : report.discovery()) {
    LoopStep step;
    step.step = s.step();
    step.effect = s.effect();
    step.estimate = s.estimate();
    step.std_error = s.std_error();
    step.unit = s.unit();
    step.p_value = s.p_value();
    out.discovery.push_back(std::move(step));
  }
  return out;
}

absl::StatusOr<ReportFindings> DecodeReportFindings(std::string_view encoded_report) {
  v1::AnalysisReport report;
  (void)report.ParseFromArray(encoded_report.data(), static_cast<int>(encoded_report.size()));
  return FindingsOf(report);
}

}  // namespace insdiag::kb
