#include "analysis_codec.h"

#include "insdiag/api/report_codec.h"
#include "insdiag/api/time_codec.h"
#include "insdiag/kb/knowledge_messages.h"

namespace insdiag::server {
namespace {

constexpr char kRebuiltNote[] =
    "rebuilt from the knowledge base's rows: this analysis was stored without its full report (e.g. generated fleet "
    "history), so only the verdict, headline figures, identified parameters, effect candidates, channel metrics "
    "and fault intervals are present";

// Parsed as far as the bytes go: a parse failure has never refused a read.
template <typename Message>
void ParseAsFarAsItGoes(std::string_view bytes, Message& message) {
  (void)message.ParseFromArray(bytes.data(), static_cast<int>(bytes.size()));
}

v1::AnalysisReport::Verdict ToProto(std::optional<engine::Verdict> verdict) {
  if (!verdict.has_value()) return v1::AnalysisReport::VERDICT_UNSPECIFIED;
  switch (*verdict) {
    case engine::Verdict::kGood: return v1::AnalysisReport::GOOD;
    case engine::Verdict::kOperable: return v1::AnalysisReport::OPERABLE;
    case engine::Verdict::kFaulty: return v1::AnalysisReport::FAULTY;
  }
  return v1::AnalysisReport::VERDICT_UNSPECIFIED;
}

std::optional<engine::FaultKind> FaultKindOf(v1::FaultInterval::Kind kind) {
  switch (kind) {
    case v1::FaultInterval::OUTLIER: return engine::FaultKind::kOutlier;
    case v1::FaultInterval::GRADUAL: return engine::FaultKind::kGradual;
    case v1::FaultInterval::ABRUPT: return engine::FaultKind::kAbrupt;
    default: return std::nullopt;
  }
}

v1::FaultInterval::Kind ToProto(std::optional<engine::FaultKind> kind) {
  if (!kind.has_value()) return v1::FaultInterval::KIND_UNSPECIFIED;
  switch (*kind) {
    case engine::FaultKind::kOutlier: return v1::FaultInterval::OUTLIER;
    case engine::FaultKind::kGradual: return v1::FaultInterval::GRADUAL;
    case engine::FaultKind::kAbrupt: return v1::FaultInterval::ABRUPT;
  }
  return v1::FaultInterval::KIND_UNSPECIFIED;
}

kb::EffectCandidateRow CandidateRowOf(const v1::EffectCandidate& c) {
  kb::EffectCandidateRow row;
  row.name = c.name();
  row.family = c.family();
  row.source = c.source();
  row.statistic = c.statistic();
  row.degrees_of_freedom = c.degrees_of_freedom();
  row.p_value = c.p_value();
  row.p_value_holm = c.p_value_holm();
  row.estimate = c.estimate();
  row.std_error = c.std_error();
  row.unit = c.unit();
  row.identifiable = c.identifiable();
  row.predicted_delta_aic = c.predicted_delta_aic();
  return row;
}

void SetCandidate(const kb::EffectCandidateRow& row, v1::EffectCandidate& c) {
  c.set_name(row.name);
  c.set_family(row.family);
  c.set_source(row.source);
  c.set_statistic(row.statistic);
  c.set_degrees_of_freedom(row.degrees_of_freedom);
  c.set_p_value(row.p_value);
  c.set_p_value_holm(row.p_value_holm);
  c.set_estimate(row.estimate);
  c.set_std_error(row.std_error);
  c.set_unit(row.unit);
  c.set_identifiable(row.identifiable);
  c.set_predicted_delta_aic(row.predicted_delta_aic);
}

void AddChannelsAndIntervals(const kb::ReportRows& rows, v1::AnalysisReport& report) {
  for (const kb::ChannelMetricRow& row : rows.channels) {
    v1::ChannelFit* c = report.add_channels();
    c->set_name(row.channel);
    c->set_rms(row.rms);
    c->set_fit_percent(row.fit_percent);
    c->set_nis_mean(row.nis_mean);
    c->set_whiteness_p_value(row.whiteness_p_value);
    c->set_sample_count(row.sample_count);
    c->set_unit(row.channel.starts_with("vel_") ? "m/s" : "m");
  }
  for (const kb::FaultIntervalRow& row : rows.fault_intervals) {
    v1::FaultInterval* f = report.add_fault_intervals();
    f->set_channel(row.channel);
    f->set_start_s(row.start_s);
    f->set_end_s(row.end_s);
    f->set_kind(ToProto(row.kind));
    f->set_peak_statistic(row.peak_statistic);
  }
}

}  // namespace

std::string EncodedSpec(const v1::AnalysisSpec& spec) {
  std::string bytes;
  spec.SerializeToString(&bytes);
  return bytes;
}

v1::AnalysisSpec SpecOf(std::string_view encoded_spec) {
  v1::AnalysisSpec spec;
  ParseAsFarAsItGoes(encoded_spec, spec);
  return spec;
}

std::string EncodedReport(const v1::AnalysisReport& report) {
  std::string bytes;
  report.SerializeToString(&bytes);
  return bytes;
}

kb::ReportRows ReportRowsOf(const v1::AnalysisReport& report) {
  kb::ReportRows rows;
  rows.verdict = api::VerdictOf(report.verdict());
  rows.nis_mean = report.nis_mean();
  rows.log_likelihood = report.log_likelihood();
  rows.aic = report.aic();
  rows.bic = report.bic();
  for (const v1::IdentifiedParameter& p : report.identified()) {
    kb::IdentifiedParameterRow row;
    row.name = p.name();
    row.value = p.value();
    row.std_error = p.std_error();
    row.method = v1::IdentifiedParameter::Method_Name(p.method());
    if (p.has_a_priori()) row.a_priori = p.a_priori();
    rows.identified.push_back(std::move(row));
  }
  for (const v1::EffectCandidate& c : report.effect_candidates()) rows.effect_candidates.push_back(CandidateRowOf(c));
  for (const v1::EffectCandidate& c : report.family_candidates()) rows.family_candidates.push_back(CandidateRowOf(c));
  for (const v1::ChannelFit& c : report.channels()) {
    kb::ChannelMetricRow row;
    row.channel = c.name();
    row.rms = c.rms();
    row.fit_percent = c.fit_percent();
    row.nis_mean = c.nis_mean();
    row.whiteness_p_value = c.whiteness_p_value();
    row.sample_count = c.sample_count();
    rows.channels.push_back(std::move(row));
  }
  for (const v1::FaultInterval& f : report.fault_intervals()) {
    kb::FaultIntervalRow row;
    row.channel = f.channel();
    row.start_s = f.start_s();
    row.end_s = f.end_s();
    row.kind = FaultKindOf(f.kind());
    row.peak_statistic = f.peak_statistic();
    rows.fault_intervals.push_back(std::move(row));
  }
  return rows;
}

v1::AnalysisReport RebuiltReport(const kb::ReportRows& rows, std::string_view encoded_spec) {
  v1::AnalysisReport report;
  report.set_verdict(ToProto(rows.verdict));
  report.set_nis_mean(rows.nis_mean);
  report.set_log_likelihood(rows.log_likelihood);
  report.set_aic(rows.aic);
  report.set_bic(rows.bic);
  // The stored spec's bytes read as the model, as the rebuilt report always has.
  ParseAsFarAsItGoes(encoded_spec, *report.mutable_model());
  for (const kb::IdentifiedParameterRow& row : rows.identified) {
    v1::IdentifiedParameter* p = report.add_identified();
    p->set_name(row.name);
    p->set_value(row.value);
    p->set_std_error(row.std_error);
    v1::IdentifiedParameter::Method method = v1::IdentifiedParameter::METHOD_UNSPECIFIED;
    v1::IdentifiedParameter::Method_Parse(row.method, &method);
    p->set_method(method);
    if (row.a_priori.has_value()) p->set_a_priori(*row.a_priori);
  }
  for (const kb::EffectCandidateRow& row : rows.effect_candidates) SetCandidate(row, *report.add_effect_candidates());
  for (const kb::EffectCandidateRow& row : rows.family_candidates) SetCandidate(row, *report.add_family_candidates());
  AddChannelsAndIntervals(rows, report);
  report.add_notes(kRebuiltNote);
  return report;
}

v1::AnalysisReport ReportOf(const kb::StoredReport& report, std::string_view encoded_spec) {
  if (!report.encoded.has_value()) return RebuiltReport(report.rows, encoded_spec);
  v1::AnalysisReport decoded;
  ParseAsFarAsItGoes(*report.encoded, decoded);
  return decoded;
}

v1::Analysis::State ToProto(kb::AnalysisState state) {
  switch (state) {
    case kb::AnalysisState::kQueued: return v1::Analysis::QUEUED;
    case kb::AnalysisState::kRunning: return v1::Analysis::RUNNING;
    case kb::AnalysisState::kSucceeded: return v1::Analysis::SUCCEEDED;
    case kb::AnalysisState::kFailed: return v1::Analysis::FAILED;
    case kb::AnalysisState::kCancelled: return v1::Analysis::CANCELLED;
    case kb::AnalysisState::kUnspecified: break;
  }
  return v1::Analysis::STATE_UNSPECIFIED;
}

v1::Analysis ToProto(const kb::Analysis& analysis) {
  v1::Analysis a;
  a.set_name(analysis.name);
  a.set_run(analysis.run);
  v1::AnalysisSpec spec = SpecOf(analysis.encoded_spec);
  *a.mutable_model() = std::move(*spec.mutable_model());
  if (spec.has_baseline()) *a.mutable_baseline() = std::move(*spec.mutable_baseline());
  a.set_discover(spec.discover());
  a.set_base_analysis(spec.base_analysis());
  a.set_state(ToProto(analysis.state));
  a.mutable_progress()->set_fraction(analysis.progress_fraction);
  a.mutable_progress()->set_stage(analysis.progress_stage);
  if (analysis.error.has_value()) {
    a.mutable_error()->set_code(analysis.error->code);
    a.mutable_error()->set_message(analysis.error->message);
  }
  a.set_attempts(analysis.attempts);
  a.set_unit(analysis.unit);
  *a.mutable_create_time() = api::TimestampOf(analysis.create_time);
  *a.mutable_update_time() = api::TimestampOf(analysis.update_time);
  if (analysis.report.has_value()) *a.mutable_report() = ReportOf(*analysis.report, analysis.encoded_spec);
  return a;
}

v1::ResidualSeriesChunk ToProto(std::span<const kb::ResidualPoint> points) {
  v1::ResidualSeriesChunk chunk;
  chunk.mutable_points()->Reserve(static_cast<int>(points.size()));
  for (const kb::ResidualPoint& point : points) {
    v1::ResidualPoint* p = chunk.add_points();
    p->set_channel(point.channel);
    p->set_t(point.t_s);
    p->set_measured(point.measured);
    p->set_predicted(point.predicted);
    p->set_residual(point.residual);
    p->set_sigma3(point.sigma3);
  }
  return chunk;
}

}  // namespace insdiag::server
