#include "insdiag/server/grpc_services.h"

#include <absl/strings/str_cat.h>

#include <atomic>

#include "fleet_codec.h"
#include "insdiag/engine/status_macros.h"
#include "insdiag/server/status_mapping.h"

namespace insdiag::server {
namespace {

constexpr char kRunService[] = "insdiag.v1.RunService";
constexpr char kAnalysisService[] = "insdiag.v1.AnalysisService";
constexpr char kKnowledgeService[] = "insdiag.v1.KnowledgeService";
constexpr char kFleetService[] = "insdiag.v1.FleetService";
constexpr char kAccessService[] = "insdiag.v1.AccessService";
constexpr char kLiveRunService[] = "insdiag.v1.LiveRunService";

std::string MethodName(const char* service, const char* method) { return absl::StrCat(service, ".", method); }

// A server-streaming method behind the access guard: `serve(write, stop)`
// streams through `writer` until done or `stop()` holds. A client that went
// away ends it CANCELLED and, for a watch (`stopping` given), a stopping
// server UNAVAILABLE, whatever the service returned.
template <typename Message, typename Serve>
grpc::Status ServeStream(AccessGuard& guard, grpc::ServerContext& context, const std::string& method,
                         grpc::ServerWriter<Message>& writer, const std::atomic<bool>* stopping, const Serve& serve) {
  if (auto caller = guard.Admit(context, method); !caller.ok()) return ToGrpcStatus(caller.status());
  const auto stopping_now = [stopping] { return stopping != nullptr && stopping->load(); };
  const absl::Status status = serve([&](const Message& message) { return writer.Write(message); },
                                    [&] { return context.IsCancelled() || stopping_now(); });
  if (stopping_now()) return grpc::Status(grpc::StatusCode::UNAVAILABLE, "the server is stopping; watch again");
  if (context.IsCancelled()) return grpc::Status(grpc::StatusCode::CANCELLED, "the client went away");
  return ToGrpcStatus(status);
}

}  // namespace

grpc::Status RunServiceGrpc::UploadRun(grpc::ServerContext* context,
                                       grpc::ServerReader<v1::UploadRunRequest>* reader, v1::Run* response) {
  const std::string method = MethodName(kRunService, "UploadRun");
  auto caller = guard_.Admit(*context, method);
  if (!caller.ok()) return ToGrpcStatus(caller.status());
  auto upload = runs_.StartUpload();
  v1::UploadRunRequest message;
  absl::Status status;
  while (status.ok() && reader->Read(&message)) status = upload.Accept(message);
  // Read() also ends when the client cancels or the connection drops: such
  // a stream is not finished and must store nothing.
  if (status.ok() && context->IsCancelled()) status = absl::CancelledError("the upload was cancelled; nothing was stored");
  absl::StatusOr<v1::Run> run = status.ok() ? upload.Finish() : absl::StatusOr<v1::Run>(status);
  if (run.ok()) *response = std::move(*run);
  guard_.Audit(*context, method, *caller, nullptr, run.ok() ? response : nullptr, run.status());
  return run.ok() ? grpc::Status::OK : ToGrpcStatus(run.status());
}

grpc::Status RunServiceGrpc::GetRun(grpc::ServerContext* context, const v1::GetRunRequest* request, v1::Run* response) {
  return guard_.Unary(*context, MethodName(kRunService, "GetRun"), *request, response,
                      [&](const kb::Caller&) { return runs_.GetRun(*request); });
}

grpc::Status RunServiceGrpc::ListRuns(grpc::ServerContext* context, const v1::ListRunsRequest* request,
                                      v1::ListRunsResponse* response) {
  return guard_.Unary(*context, MethodName(kRunService, "ListRuns"), *request, response,
                      [&](const kb::Caller&) { return runs_.ListRuns(*request); });
}

grpc::Status RunServiceGrpc::DeleteRun(grpc::ServerContext* context, const v1::DeleteRunRequest* request,
                                       google::protobuf::Empty* response) {
  return guard_.Unary(*context, MethodName(kRunService, "DeleteRun"), *request, response,
                      [&](const kb::Caller&) -> absl::StatusOr<google::protobuf::Empty> {
                        INSDIAG_RETURN_IF_ERROR(runs_.DeleteRun(*request));
                        return google::protobuf::Empty();
                      });
}

grpc::Status RunServiceGrpc::ReadRunSamples(grpc::ServerContext* context, const v1::ReadRunSamplesRequest* request,
                                            grpc::ServerWriter<v1::SampleChunk>* writer) {
  return ServeStream(guard_, *context, MethodName(kRunService, "ReadRunSamples"), *writer, nullptr,
                     [&](const auto& write, const auto&) { return runs_.ReadRunSamples(*request, write); });
}

grpc::Status LiveRunServiceGrpc::MonitorRun(grpc::ServerContext* context,
                                            grpc::ServerReaderWriter<v1::LiveRun, v1::MonitorRunRequest>* stream) {
  const std::string method = MethodName(kLiveRunService, "MonitorRun");
  auto caller = guard_.Admit(*context, method);
  if (!caller.ok()) return ToGrpcStatus(caller.status());
  v1::LiveRun last;
  const absl::Status status = live_.MonitorRun([&](v1::MonitorRunRequest& request) { return stream->Read(&request); },
                                               [&](const v1::LiveRun& state) { return stream->Write(state); },
                                               [&] { return context->IsCancelled(); }, last);
  // The write the audit records is the stored run.
  v1::Run stored;
  stored.set_name(last.run());
  guard_.Audit(*context, method, *caller, nullptr, status.ok() ? &stored : nullptr, status);
  return ToGrpcStatus(status);
}

grpc::Status LiveRunServiceGrpc::ListLiveRuns(grpc::ServerContext* context, const v1::ListLiveRunsRequest* request,
                                              v1::ListLiveRunsResponse* response) {
  return guard_.Unary(*context, MethodName(kLiveRunService, "ListLiveRuns"), *request, response,
                      [&](const kb::Caller&) { return live_.ListLiveRuns(*request); });
}

grpc::Status LiveRunServiceGrpc::WatchLiveRun(grpc::ServerContext* context, const v1::WatchLiveRunRequest* request,
                                              grpc::ServerWriter<v1::LiveRun>* writer) {
  return ServeStream(guard_, *context, MethodName(kLiveRunService, "WatchLiveRun"), *writer, &stopping_,
                     [&](const auto& write, const auto& stop) { return live_.WatchLiveRun(*request, write, stop); });
}

// Defines a unary adapter: `Class::Name` of `service` delegating to
// `target.Name(*request)` behind the access guard.
#define INSDIAG_DELEGATE(Class, service, target, Name, Request, Response)                                       \
  grpc::Status Class::Name(grpc::ServerContext* context, const v1::Request* request, v1::Response* response) { \
    return guard_.Unary(*context, MethodName(service, #Name), *request, response,                              \
                        [&](const kb::Caller&) { return target.Name(*request); });                              \
  }
// As INSDIAG_DELEGATE, passing the caller on: `target.Name(*request, caller)`.
#define INSDIAG_DELEGATE_WITH_CALLER(Class, service, target, Name, Request, Response)                            \
  grpc::Status Class::Name(grpc::ServerContext* context, const v1::Request* request, v1::Response* response) { \
    return guard_.Unary(*context, MethodName(service, #Name), *request, response,                              \
                        [&](const kb::Caller& caller) { return target.Name(*request, caller); });               \
  }
// As INSDIAG_DELEGATE over a store of domain values: the request mapped to
// its query and the result to the response (FromProto, ToProto).
#define INSDIAG_DELEGATE_MAPPED(Class, service, target, Name, Request, Response)                               \
  grpc::Status Class::Name(grpc::ServerContext* context, const v1::Request* request, v1::Response* response) { \
    return guard_.Unary(*context, MethodName(service, #Name), *request, response,                              \
                        [&](const kb::Caller&) -> absl::StatusOr<v1::Response> {                               \
                          INSDIAG_ASSIGN_OR_RETURN(auto result, target.Name(FromProto(*request)));              \
                          return ToProto(result);                                                              \
                        });                                                                                    \
  }

INSDIAG_DELEGATE(AnalysisServiceGrpc, kAnalysisService, analyses_, CreateAnalysis, CreateAnalysisRequest, Analysis)
INSDIAG_DELEGATE(AnalysisServiceGrpc, kAnalysisService, analyses_, GetAnalysis, GetAnalysisRequest, Analysis)
INSDIAG_DELEGATE(AnalysisServiceGrpc, kAnalysisService, analyses_, ListAnalyses, ListAnalysesRequest, ListAnalysesResponse)
INSDIAG_DELEGATE(AnalysisServiceGrpc, kAnalysisService, analyses_, CancelAnalysis, CancelAnalysisRequest, Analysis)
INSDIAG_DELEGATE(AnalysisServiceGrpc, kAnalysisService, analyses_, ReadDisplaySeries, ReadDisplaySeriesRequest, DisplaySeries)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, kKnowledgeService, knowledge_, GetUnitType, GetUnitTypeRequest, UnitType)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, kKnowledgeService, knowledge_, ListUnitTypes, ListUnitTypesRequest, ListUnitTypesResponse)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, kKnowledgeService, knowledge_, GetUnit, GetUnitRequest, Unit)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, kKnowledgeService, knowledge_, ListUnits, ListUnitsRequest, ListUnitsResponse)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, kKnowledgeService, knowledge_, ListModules, ListModulesRequest, ListModulesResponse)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, kKnowledgeService, knowledge_, GetUnitHistory, GetUnitHistoryRequest, UnitHistory)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, kKnowledgeService, knowledge_, ListFailureModes, ListFailureModesRequest, ListFailureModesResponse)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, kKnowledgeService, knowledge_, GetFailureMode, GetFailureModeRequest, FailureMode)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, kKnowledgeService, knowledge_, CreateFailureRecord, CreateFailureRecordRequest, FailureRecord)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, kKnowledgeService, knowledge_, CorrectFailureRecord, CorrectFailureRecordRequest,
                 FailureRecord)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, kKnowledgeService, knowledge_, ListFailureRecordRevisions,
                 ListFailureRecordRevisionsRequest, ListFailureRecordRevisionsResponse)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, kKnowledgeService, knowledge_, ListFailureRecords, ListFailureRecordsRequest,
                 ListFailureRecordsResponse)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, kKnowledgeService, knowledge_, CreateDiagnosis, CreateDiagnosisRequest, Diagnosis)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, kKnowledgeService, knowledge_, GetDiagnosis, GetDiagnosisRequest, Diagnosis)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, kKnowledgeService, knowledge_, ListDiagnoses, ListDiagnosesRequest, ListDiagnosesResponse)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, kKnowledgeService, knowledge_, ResolveDiagnosis, ResolveDiagnosisRequest, Diagnosis)
INSDIAG_DELEGATE_MAPPED(FleetServiceGrpc, kFleetService, fleet_, GetFleetStatistics, GetFleetStatisticsRequest,
                        FleetStatistics)
INSDIAG_DELEGATE_MAPPED(FleetServiceGrpc, kFleetService, fleet_, ListFailureCounts, ListFailureCountsRequest,
                        ListFailureCountsResponse)
INSDIAG_DELEGATE_MAPPED(FleetServiceGrpc, kFleetService, fleet_, GetFailurePareto, GetFailureParetoRequest, FailurePareto)
INSDIAG_DELEGATE_MAPPED(FleetServiceGrpc, kFleetService, fleet_, GetWeibullFit, GetWeibullFitRequest, WeibullFit)
INSDIAG_DELEGATE_MAPPED(FleetServiceGrpc, kFleetService, fleet_, ListParameterTrends, ListParameterTrendsRequest,
                        ListParameterTrendsResponse)
INSDIAG_DELEGATE_MAPPED(FleetServiceGrpc, kFleetService, fleet_, GetParameterTrend, GetParameterTrendRequest,
                        ParameterTrend)
INSDIAG_DELEGATE_MAPPED(FleetServiceGrpc, kFleetService, fleet_, RankUnits, RankUnitsRequest, RankUnitsResponse)

INSDIAG_DELEGATE_WITH_CALLER(AccessServiceGrpc, kAccessService, access_, GetCaller, GetCallerRequest, Caller)
INSDIAG_DELEGATE_WITH_CALLER(AccessServiceGrpc, kAccessService, access_, CreateToken, CreateTokenRequest, CreatedToken)
INSDIAG_DELEGATE_WITH_CALLER(AccessServiceGrpc, kAccessService, access_, ListTokens, ListTokensRequest, ListTokensResponse)
INSDIAG_DELEGATE_WITH_CALLER(AccessServiceGrpc, kAccessService, access_, RevokeToken, RevokeTokenRequest, Token)
INSDIAG_DELEGATE_WITH_CALLER(AccessServiceGrpc, kAccessService, access_, ListAuditEvents, ListAuditEventsRequest,
                             ListAuditEventsResponse)

#undef INSDIAG_DELEGATE
#undef INSDIAG_DELEGATE_WITH_CALLER
#undef INSDIAG_DELEGATE_MAPPED

grpc::Status AnalysisServiceGrpc::GetTestReport(grpc::ServerContext* context, const v1::GetTestReportRequest* request,
                                                google::api::HttpBody* response) {
  return guard_.Unary(*context, MethodName(kAnalysisService, "GetTestReport"), *request, response,
                      [&](const kb::Caller&) { return test_reports_.GetTestReport(*request); });
}

grpc::Status AnalysisServiceGrpc::WatchAnalysis(grpc::ServerContext* context, const v1::WatchAnalysisRequest* request,
                                                grpc::ServerWriter<v1::Analysis>* writer) {
  return ServeStream(guard_, *context, MethodName(kAnalysisService, "WatchAnalysis"), *writer, &stopping_,
                     [&](const auto& write, const auto& stop) { return analyses_.WatchAnalysis(*request, write, stop); });
}

grpc::Status AnalysisServiceGrpc::ReadResidualSeries(grpc::ServerContext* context,
                                                     const v1::ReadResidualSeriesRequest* request,
                                                     grpc::ServerWriter<v1::ResidualSeriesChunk>* writer) {
  return ServeStream(guard_, *context, MethodName(kAnalysisService, "ReadResidualSeries"), *writer, nullptr,
                     [&](const auto& write, const auto&) { return analyses_.ReadResidualSeries(*request, write); });
}

}  // namespace insdiag::server
