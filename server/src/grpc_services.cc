#include "insdiag/server/grpc_services.h"

#include "insdiag/server/status_mapping.h"

namespace insdiag::server {
namespace {

template <typename Response>
grpc::Status Respond(absl::StatusOr<Response> result, Response* response) {
  if (!result.ok()) return ToGrpcStatus(result.status());
  *response = std::move(*result);
  return grpc::Status::OK;
}

}  // namespace

grpc::Status RunServiceGrpc::UploadRun(grpc::ServerContext* context,
                                       grpc::ServerReader<v1::UploadRunRequest>* reader, v1::Run* response) {
  auto upload = runs_.StartUpload();
  v1::UploadRunRequest message;
  while (reader->Read(&message)) {
    if (auto status = upload.Accept(message); !status.ok()) return ToGrpcStatus(status);
  }
  // Read() also ends when the client cancels or the connection drops: such
  // a stream is not finished and must store nothing.
  if (context->IsCancelled()) {
    return grpc::Status(grpc::StatusCode::CANCELLED, "the upload was cancelled; nothing was stored");
  }
  return Respond(upload.Finish(), response);
}

grpc::Status RunServiceGrpc::GetRun(grpc::ServerContext*, const v1::GetRunRequest* request, v1::Run* response) {
  return Respond(runs_.GetRun(*request), response);
}

grpc::Status RunServiceGrpc::ListRuns(grpc::ServerContext*, const v1::ListRunsRequest* request,
                                      v1::ListRunsResponse* response) {
  return Respond(runs_.ListRuns(*request), response);
}

grpc::Status RunServiceGrpc::DeleteRun(grpc::ServerContext*, const v1::DeleteRunRequest* request,
                                       google::protobuf::Empty*) {
  return ToGrpcStatus(runs_.DeleteRun(*request));
}

grpc::Status RunServiceGrpc::ReadRunSamples(grpc::ServerContext* context, const v1::ReadRunSamplesRequest* request,
                                            grpc::ServerWriter<v1::SampleChunk>* writer) {
  const absl::Status status =
      runs_.ReadRunSamples(*request, [&](const v1::SampleChunk& chunk) { return writer->Write(chunk); });
  if (context->IsCancelled()) return grpc::Status(grpc::StatusCode::CANCELLED, "the client went away");
  return ToGrpcStatus(status);
}

// Defines a unary adapter: `Class::Name` delegating to `target.Name(*request)`.
#define INSDIAG_DELEGATE(Class, target, Name, Request, Response)                                         \
  grpc::Status Class::Name(grpc::ServerContext*, const v1::Request* request, v1::Response* response) { \
    return Respond(target.Name(*request), response);                                                  \
  }

INSDIAG_DELEGATE(AnalysisServiceGrpc, analyses_, CreateAnalysis, CreateAnalysisRequest, Analysis)
INSDIAG_DELEGATE(AnalysisServiceGrpc, analyses_, GetAnalysis, GetAnalysisRequest, Analysis)
INSDIAG_DELEGATE(AnalysisServiceGrpc, analyses_, ListAnalyses, ListAnalysesRequest, ListAnalysesResponse)
INSDIAG_DELEGATE(AnalysisServiceGrpc, analyses_, CancelAnalysis, CancelAnalysisRequest, Analysis)
INSDIAG_DELEGATE(AnalysisServiceGrpc, analyses_, ReadDisplaySeries, ReadDisplaySeriesRequest, DisplaySeries)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, knowledge_, GetUnitType, GetUnitTypeRequest, UnitType)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, knowledge_, ListUnitTypes, ListUnitTypesRequest, ListUnitTypesResponse)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, knowledge_, GetUnit, GetUnitRequest, Unit)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, knowledge_, ListUnits, ListUnitsRequest, ListUnitsResponse)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, knowledge_, ListModules, ListModulesRequest, ListModulesResponse)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, knowledge_, ListFailureModes, ListFailureModesRequest, ListFailureModesResponse)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, knowledge_, GetFailureMode, GetFailureModeRequest, FailureMode)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, knowledge_, CreateFailureRecord, CreateFailureRecordRequest, FailureRecord)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, knowledge_, ListFailureRecords, ListFailureRecordsRequest,
                 ListFailureRecordsResponse)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, knowledge_, CreateDiagnosis, CreateDiagnosisRequest, Diagnosis)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, knowledge_, GetDiagnosis, GetDiagnosisRequest, Diagnosis)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, knowledge_, ListDiagnoses, ListDiagnosesRequest, ListDiagnosesResponse)
INSDIAG_DELEGATE(KnowledgeServiceGrpc, knowledge_, ResolveDiagnosis, ResolveDiagnosisRequest, Diagnosis)
INSDIAG_DELEGATE(FleetServiceGrpc, fleet_, GetFleetStatistics, GetFleetStatisticsRequest, FleetStatistics)
INSDIAG_DELEGATE(FleetServiceGrpc, fleet_, ListFailureCounts, ListFailureCountsRequest, ListFailureCountsResponse)
INSDIAG_DELEGATE(FleetServiceGrpc, fleet_, GetFailurePareto, GetFailureParetoRequest, FailurePareto)
INSDIAG_DELEGATE(FleetServiceGrpc, fleet_, GetWeibullFit, GetWeibullFitRequest, WeibullFit)
INSDIAG_DELEGATE(FleetServiceGrpc, fleet_, ListParameterTrends, ListParameterTrendsRequest,
                 ListParameterTrendsResponse)
INSDIAG_DELEGATE(FleetServiceGrpc, fleet_, GetParameterTrend, GetParameterTrendRequest, ParameterTrend)
INSDIAG_DELEGATE(FleetServiceGrpc, fleet_, RankUnits, RankUnitsRequest, RankUnitsResponse)

#undef INSDIAG_DELEGATE

grpc::Status AnalysisServiceGrpc::WatchAnalysis(grpc::ServerContext* context, const v1::WatchAnalysisRequest* request,
                                                grpc::ServerWriter<v1::Analysis>* writer) {
  const absl::Status status = analyses_.WatchAnalysis(
      *request, [&](const v1::Analysis& analysis) { return writer->Write(analysis); },
      [context] { return context->IsCancelled(); });
  if (context->IsCancelled()) return grpc::Status(grpc::StatusCode::CANCELLED, "the client went away");
  return ToGrpcStatus(status);
}

grpc::Status AnalysisServiceGrpc::ReadResidualSeries(grpc::ServerContext* context,
                                                     const v1::ReadResidualSeriesRequest* request,
                                                     grpc::ServerWriter<v1::ResidualSeriesChunk>* writer) {
  const absl::Status status = analyses_.ReadResidualSeries(
      *request, [&](const v1::ResidualSeriesChunk& chunk) { return writer->Write(chunk); });
  if (context->IsCancelled()) return grpc::Status(grpc::StatusCode::CANCELLED, "the client went away");
  return ToGrpcStatus(status);
}

}  // namespace insdiag::server
