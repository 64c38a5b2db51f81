#include "insdiag/server/kb_services.h"

#include <absl/strings/str_cat.h>

#include <algorithm>
#include <map>
#include <thread>

#include "access_codec.h"
#include "analysis_codec.h"
#include "history_codec.h"
#include "insdiag/api/report_codec.h"
#include "insdiag/api/resource_names.h"
#include "insdiag/engine/model/effect_catalogue.h"
#include "insdiag/engine/status_macros.h"
#include "insdiag/kb/diagnose_analysis.h"
#include "insdiag/kb/knowledge_messages.h"
#include "insdiag/server/analysis_job.h"
#include "insdiag/server/display_series.h"
#include "knowledge_codec.h"

namespace insdiag::server {
namespace {

bool Terminal(v1::Analysis::State s) {
  return s == v1::Analysis::SUCCEEDED || s == v1::Analysis::FAILED || s == v1::Analysis::CANCELLED;
}

absl::Status CheckPageSize(int page_size) {
  if (page_size < 0) return absl::InvalidArgumentError("page_size must not be negative");
  return absl::OkStatus();
}

// Every effect named against the engine's catalogue, before the analysis is
// queued: a worker would fail on it later, after the user has gone.
absl::Status CheckEffectNames(const google::protobuf::RepeatedPtrField<std::string>& effects, const char* field) {
  for (int i = 0; i < effects.size(); ++i) {
    if (auto terms = engine::ParseEffectSelector(effects[i]); !terms.ok()) {
      return absl::InvalidArgumentError(absl::StrCat(field, "[", i, "]: ", terms.status().message()));
    }
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<v1::Analysis> AnalysisService::CreateAnalysis(const v1::CreateAnalysisRequest& request) {
  const std::string& run = request.analysis().run();
  if (run.empty()) return absl::InvalidArgumentError("analysis.run: required (runs/{run})");
  INSDIAG_ASSIGN_OR_RETURN(auto run_id, api::ResourceId(run, api::kRuns, "analysis.run"));
  INSDIAG_RETURN_IF_ERROR(CheckEffectNames(request.analysis().model().effects(), "analysis.model.effects"));
  INSDIAG_RETURN_IF_ERROR(CheckEffectNames(request.analysis().baseline().effects(), "analysis.baseline.effects"));
  v1::AnalysisSpec spec;
  *spec.mutable_model() = request.analysis().model();
  if (request.analysis().has_baseline()) *spec.mutable_baseline() = request.analysis().baseline();
  spec.set_discover(request.analysis().discover());
  if (!request.analysis().base_analysis().empty()) {
    INSDIAG_RETURN_IF_ERROR(CheckBaseAnalysis(request.analysis(), spec));
  }
  INSDIAG_ASSIGN_OR_RETURN(auto created, store_.Create(run_id, EncodedSpec(spec), request.request_id()));
  if (options_.queued) options_.queued();
  return ToProto(created);
}

// An analysis that starts from an earlier one's identified model: the earlier
// one succeeded on the same run, and the baseline is (within) its model.
absl::Status AnalysisService::CheckBaseAnalysis(const v1::Analysis& asked, v1::AnalysisSpec& spec) {
  INSDIAG_ASSIGN_OR_RETURN(
      auto id, api::ResourceId(asked.base_analysis(), api::kAnalyses, "analysis.base_analysis"));
  INSDIAG_ASSIGN_OR_RETURN(auto stored_base, store_.Get(id, true));
  const v1::Analysis base = ToProto(stored_base);
  if (base.run() != asked.run()) {
    return absl::InvalidArgumentError(
        absl::StrCat("analysis.base_analysis: ", asked.base_analysis(), " analysed ", base.run(),
                     ", not ", asked.run()));
  }
  if (base.state() != v1::Analysis::SUCCEEDED) {
    return absl::FailedPreconditionError(absl::StrCat("analysis.base_analysis: ", asked.base_analysis(),
                                                      " has not succeeded: it has no identified model to start from"));
  }
  INSDIAG_ASSIGN_OR_RETURN(auto identified, api::IdentifiedModelOf(base.report()));
  for (int i = 0; i < spec.baseline().effects_size(); ++i) {
    const std::string& effect = spec.baseline().effects(i);
    auto terms = engine::ParseEffectSelector(effect);
    const bool covered =
        terms.ok() && std::all_of(terms->begin(), terms->end(), [&](const engine::EffectTerm& t) {
          return identified.model.FindEffect(t) >= 0;
        });
    if (!covered) {
      return absl::InvalidArgumentError(absl::StrCat("analysis.baseline.effects[", i, "]: '", effect, "' is not in ",
                                                     asked.base_analysis(), "'s model"));
    }
  }
  DefaultBaselineToBase(base, spec);
  spec.set_base_analysis(asked.base_analysis());
  return absl::OkStatus();
}

absl::StatusOr<v1::Analysis> AnalysisService::GetAnalysis(const v1::GetAnalysisRequest& request) {
  INSDIAG_ASSIGN_OR_RETURN(auto id, api::ResourceId(request.name(), api::kAnalyses));
  INSDIAG_ASSIGN_OR_RETURN(auto analysis, store_.Get(id, true));
  return ToProto(analysis);
}

absl::StatusOr<v1::ListAnalysesResponse> AnalysisService::ListAnalyses(const v1::ListAnalysesRequest& request) {
  INSDIAG_RETURN_IF_ERROR(CheckPageSize(request.page_size()));
  kb::AnalysisQuery query;
  query.page_size = request.page_size();
  query.page_token = request.page_token();
  query.include_reports = request.include_reports();
  if (!request.run().empty()) {
    auto run_id = api::ResourceId(request.run(), api::kRuns, "run");
    if (!run_id.ok()) return run_id.status();
    query.run_id = *std::move(run_id);
  }
  if (!request.unit().empty()) {
    INSDIAG_ASSIGN_OR_RETURN(auto serial, api::ResourceId(request.unit(), api::kUnits, "unit"));
    query.unit_serial = std::move(serial);
  }
  INSDIAG_ASSIGN_OR_RETURN(auto page, store_.List(query));
  v1::ListAnalysesResponse response;
  for (const kb::Analysis& a : page.analyses) *response.add_analyses() = ToProto(a);
  response.set_next_page_token(page.next_page_token);
  return response;
}

absl::StatusOr<v1::Analysis> AnalysisService::CancelAnalysis(const v1::CancelAnalysisRequest& request) {
  INSDIAG_ASSIGN_OR_RETURN(auto id, api::ResourceId(request.name(), api::kAnalyses));
  INSDIAG_ASSIGN_OR_RETURN(auto cancelled, store_.Cancel(id));
  return ToProto(cancelled);
}

absl::Status AnalysisService::WatchAnalysis(const v1::WatchAnalysisRequest& request,
                                            absl::FunctionRef<bool(const v1::Analysis&)> send,
                                            std::function<bool()> stop) {
  INSDIAG_ASSIGN_OR_RETURN(auto id, api::ResourceId(request.name(), api::kAnalyses));
  std::string last;
  for (;;) {
    INSDIAG_ASSIGN_OR_RETURN(auto stored, store_.Get(id, false));
    const v1::Analysis analysis = ToProto(stored);
    const bool terminal = Terminal(analysis.state());
    if (terminal) {
      auto full = store_.Get(id, true);  // the last message carries the report
      if (!full.ok()) return full.status();
      send(ToProto(*full));
      return absl::OkStatus();
    }
    const std::string key = absl::StrCat(analysis.state(), "|", analysis.progress().fraction(), "|",
                                         analysis.progress().stage(), "|", analysis.attempts());
    if (key != last) {
      last = key;
      if (!send(analysis)) return absl::OkStatus();
    }
    if (stop && stop()) return absl::CancelledError("the watch was cancelled");
    std::this_thread::sleep_for(options_.watch_poll);
  }
}

absl::Status AnalysisService::ReadResidualSeries(const v1::ReadResidualSeriesRequest& request,
                                                 absl::FunctionRef<bool(const v1::ResidualSeriesChunk&)> send) {
  INSDIAG_ASSIGN_OR_RETURN(auto id, api::ResourceId(request.name(), api::kAnalyses));
  if (request.chunk_size() < 0 || request.chunk_size() > 50'000) {
    return absl::InvalidArgumentError("chunk_size must be within 0 … 50000");
  }
  const std::vector<std::string> channels(request.channels().begin(), request.channels().end());
  return store_.ReadSeries(id, channels,
                           request.chunk_size() == 0 ? 5000 : static_cast<std::size_t>(request.chunk_size()),
                           [&](std::span<const kb::ResidualPoint> points) { return send(ToProto(points)); });
}

absl::StatusOr<v1::DisplaySeries> AnalysisService::ReadDisplaySeries(const v1::ReadDisplaySeriesRequest& request) {
  constexpr int kDefaultColumns = 1000;
  constexpr int kMaxColumns = 20'000;
  if (request.columns() < 0 || request.columns() > kMaxColumns) {
    return absl::InvalidArgumentError(absl::StrCat("columns must be within 0 … ", kMaxColumns, " (0: ",
                                                   kDefaultColumns, ")"));
  }
  const bool whole = request.start_s() == 0 && request.end_s() == 0;
  if (!whole && !(request.end_s() > request.start_s())) {
    return absl::InvalidArgumentError(absl::StrCat("end_s (", request.end_s(), ") must be after start_s (",
                                                   request.start_s(), "); both 0 ask for the whole series"));
  }
  INSDIAG_ASSIGN_OR_RETURN(auto id, api::ResourceId(request.name(), api::kAnalyses));
  // The stored series arrives channel by channel, each in time order.
  std::vector<std::string> order;
  std::map<std::string, std::vector<SeriesEpoch>> epochs;
  const std::vector<std::string> channels(request.channels().begin(), request.channels().end());
  auto read = store_.ReadSeries(id, channels, 50'000, [&](std::span<const kb::ResidualPoint> points) {
    for (const kb::ResidualPoint& p : points) {
      auto [it, inserted] = epochs.try_emplace(p.channel);
      if (inserted) order.push_back(p.channel);
      it->second.push_back({p.t_s, p.measured, p.predicted, p.residual, p.sigma3});
    }
    return true;
  });
  if (!read.ok()) return read;
  v1::DisplaySeries out;
  out.set_name(request.name());
  out.set_columns(request.columns() == 0 ? kDefaultColumns : request.columns());
  for (const auto& [channel, series] : epochs) {
    if (series.empty()) continue;
    if (out.series_start_s() == 0 && out.series_end_s() == 0) {
      out.set_series_start_s(series.front().t);
      out.set_series_end_s(series.back().t);
    }
    out.set_series_start_s(std::min(out.series_start_s(), series.front().t));
    out.set_series_end_s(std::max(out.series_end_s(), series.back().t));
  }
  out.set_start_s(whole ? out.series_start_s() : request.start_s());
  out.set_end_s(whole ? out.series_end_s() : request.end_s());
  for (const auto& channel : order) {
    INSDIAG_ASSIGN_OR_RETURN(auto envelope, DecimateForDisplay(epochs[channel], out.start_s(),
                                                               out.end_s(), out.columns()));
    envelope.set_channel(channel);
    *out.add_channels() = std::move(envelope);
  }
  return out;
}

absl::StatusOr<v1::UnitType> KnowledgeService::GetUnitType(const v1::GetUnitTypeRequest& request) {
  INSDIAG_ASSIGN_OR_RETURN(const kb::UnitType unit_type, catalogue_.GetUnitType(request.name()));
  return kb::ToProto(unit_type);
}

absl::StatusOr<v1::ListUnitTypesResponse> KnowledgeService::ListUnitTypes(const v1::ListUnitTypesRequest& request) {
  INSDIAG_RETURN_IF_ERROR(CheckPageSize(request.page_size()));
  INSDIAG_ASSIGN_OR_RETURN(auto types, catalogue_.ListUnitTypes());
  v1::ListUnitTypesResponse response;
  for (const kb::UnitType& t : types) *response.add_unit_types() = kb::ToProto(t);
  return response;
}

absl::StatusOr<v1::UnitHistory> KnowledgeService::GetUnitHistory(const v1::GetUnitHistoryRequest& request) {
  INSDIAG_ASSIGN_OR_RETURN(const kb::UnitHistory history, history_.Get(UnitHistoryQueryOf(request)));
  return ToProto(history);
}

absl::StatusOr<v1::Unit> KnowledgeService::GetUnit(const v1::GetUnitRequest& request) {
  INSDIAG_ASSIGN_OR_RETURN(const kb::Unit unit, catalogue_.GetUnit(request.name()));
  return ToProto(unit);
}

absl::StatusOr<v1::ListUnitsResponse> KnowledgeService::ListUnits(const v1::ListUnitsRequest& request) {
  INSDIAG_RETURN_IF_ERROR(CheckPageSize(request.page_size()));
  INSDIAG_ASSIGN_OR_RETURN(auto page,
                           catalogue_.ListUnits({request.page_size(), request.page_token()},
                                                request.unit_type(), request.batch()));
  v1::ListUnitsResponse response;
  for (const kb::Unit& u : page.first) *response.add_units() = ToProto(u);
  response.set_next_page_token(page.second);
  return response;
}

absl::StatusOr<v1::ListModulesResponse> KnowledgeService::ListModules(const v1::ListModulesRequest& request) {
  INSDIAG_ASSIGN_OR_RETURN(auto modules, catalogue_.ListModules(request.parent()));
  v1::ListModulesResponse response;
  for (const kb::Module& m : modules) *response.add_modules() = ToProto(m);
  return response;
}

absl::StatusOr<v1::ListFailureModesResponse> KnowledgeService::ListFailureModes(
    const v1::ListFailureModesRequest& request) {
  INSDIAG_RETURN_IF_ERROR(CheckPageSize(request.page_size()));
  INSDIAG_ASSIGN_OR_RETURN(auto modes,
                           catalogue_.ListFailureModes(request.unit_type(), request.module_role()));
  v1::ListFailureModesResponse response;
  for (const kb::FailureMode& m : modes) *response.add_failure_modes() = kb::ToProto(m);
  return response;
}

absl::StatusOr<v1::FailureMode> KnowledgeService::GetFailureMode(const v1::GetFailureModeRequest& request) {
  INSDIAG_ASSIGN_OR_RETURN(const kb::FailureMode mode, catalogue_.GetFailureMode(request.name()));
  return kb::ToProto(mode);
}

absl::StatusOr<v1::FailureRecord> KnowledgeService::CreateFailureRecord(const v1::CreateFailureRecordRequest& request) {
  INSDIAG_ASSIGN_OR_RETURN(const kb::FailureRecord created, records_.Create(FromProto(request.failure_record())));
  return ToProto(created);
}

absl::StatusOr<v1::FailureRecord> KnowledgeService::CorrectFailureRecord(
    const v1::CorrectFailureRecordRequest& request) {
  INSDIAG_ASSIGN_OR_RETURN(const kb::FailureRecord corrected,
                           records_.Correct(request.name(), FromProto(request.failure_record()), request.reason()));
  return ToProto(corrected);
}

absl::StatusOr<v1::ListFailureRecordRevisionsResponse> KnowledgeService::ListFailureRecordRevisions(
    const v1::ListFailureRecordRevisionsRequest& request) {
  INSDIAG_ASSIGN_OR_RETURN(auto revisions, records_.ListRevisions(request.name()));
  v1::ListFailureRecordRevisionsResponse response;
  for (const kb::FailureRecordRevision& revision : revisions) *response.add_revisions() = ToProto(revision);
  return response;
}

absl::StatusOr<v1::ListFailureRecordsResponse> KnowledgeService::ListFailureRecords(
    const v1::ListFailureRecordsRequest& request) {
  INSDIAG_RETURN_IF_ERROR(CheckPageSize(request.page_size()));
  kb::FailureRecordQuery query;
  query.page = {request.page_size(), request.page_token()};
  query.module = request.module();
  query.unit = request.unit();
  query.failure_mode = request.failure_mode();
  INSDIAG_ASSIGN_OR_RETURN(auto page, records_.List(query));
  v1::ListFailureRecordsResponse response;
  for (const kb::FailureRecord& r : page.first) *response.add_failure_records() = ToProto(r);
  response.set_next_page_token(page.second);
  return response;
}

absl::StatusOr<v1::Diagnosis> KnowledgeService::CreateDiagnosis(const v1::CreateDiagnosisRequest& request) {
  if (request.analysis().empty()) return absl::InvalidArgumentError("analysis: required (analyses/{analysis})");
  INSDIAG_ASSIGN_OR_RETURN(const kb::StoredDiagnosis stored,
                           kb::AnalysisDiagnoser(diagnoses_, kb::EncodeDiagnosis).Diagnose(request.analysis()));
  return kb::DecodeDiagnosis(stored);
}

absl::StatusOr<v1::Diagnosis> KnowledgeService::GetDiagnosis(const v1::GetDiagnosisRequest& request) {
  INSDIAG_ASSIGN_OR_RETURN(const kb::StoredDiagnosis stored, diagnoses_.Get(request.name()));
  return kb::DecodeDiagnosis(stored);
}

absl::StatusOr<v1::ListDiagnosesResponse> KnowledgeService::ListDiagnoses(const v1::ListDiagnosesRequest& request) {
  INSDIAG_RETURN_IF_ERROR(CheckPageSize(request.page_size()));
  kb::DiagnosisQuery query;
  query.page = {request.page_size(), request.page_token()};
  query.analysis = request.analysis();
  query.unit = request.unit();
  INSDIAG_ASSIGN_OR_RETURN(auto page, diagnoses_.List(query));
  v1::ListDiagnosesResponse response;
  for (const kb::StoredDiagnosis& stored : page.first) {
    INSDIAG_ASSIGN_OR_RETURN(*response.add_diagnoses(), kb::DecodeDiagnosis(stored));
  }
  response.set_next_page_token(page.second);
  return response;
}

absl::StatusOr<v1::Diagnosis> KnowledgeService::ResolveDiagnosis(const v1::ResolveDiagnosisRequest& request) {
  INSDIAG_ASSIGN_OR_RETURN(const kb::StoredDiagnosis stored, diagnoses_.Resolve(ResolutionOf(request)));
  return kb::DecodeDiagnosis(stored);
}

absl::StatusOr<v1::Caller> AccessService::GetCaller(const v1::GetCallerRequest&, const kb::Caller& caller) {
  return ToProto(caller);
}

absl::StatusOr<v1::CreatedToken> AccessService::CreateToken(const v1::CreateTokenRequest& request,
                                                            const kb::Caller& caller) {
  INSDIAG_ASSIGN_OR_RETURN(auto created, store_.CreateToken(FromProto(request.token()), caller.token));
  return ToProto(created);
}

absl::StatusOr<v1::ListTokensResponse> AccessService::ListTokens(const v1::ListTokensRequest& request,
                                                                 const kb::Caller&) {
  INSDIAG_RETURN_IF_ERROR(CheckPageSize(request.page_size()));
  INSDIAG_ASSIGN_OR_RETURN(auto page, store_.ListTokens({.page_size = request.page_size(),
                                                         .page_token = request.page_token()}));
  v1::ListTokensResponse response;
  for (const kb::Token& token : page.first) *response.add_tokens() = ToProto(token);
  response.set_next_page_token(page.second);
  return response;
}

absl::StatusOr<v1::Token> AccessService::RevokeToken(const v1::RevokeTokenRequest& request, const kb::Caller&) {
  INSDIAG_ASSIGN_OR_RETURN(auto revoked, store_.RevokeToken(request.name()));
  return ToProto(revoked);
}

absl::StatusOr<v1::ListAuditEventsResponse> AccessService::ListAuditEvents(const v1::ListAuditEventsRequest& request,
                                                                           const kb::Caller&) {
  INSDIAG_RETURN_IF_ERROR(CheckPageSize(request.page_size()));
  INSDIAG_ASSIGN_OR_RETURN(auto page,
                           store_.ListAuditEvents({.page = {.page_size = request.page_size(),
                                                            .page_token = request.page_token()},
                                                   .resource = request.resource(),
                                                   .token = request.token()}));
  v1::ListAuditEventsResponse response;
  for (const kb::AuditEvent& event : page.first) *response.add_audit_events() = ToProto(event);
  response.set_next_page_token(page.second);
  return response;
}

}  // namespace insdiag::server
