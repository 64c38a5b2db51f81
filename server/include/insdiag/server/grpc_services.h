// The gRPC face: thin adapters from the generated service bases onto the
// transport-free services. Every method passes the access guard
// (access_guard.h) and maps its errors by ToGrpcStatus. The watching
// streams end when their client goes or when `stopping` is set (the server
// is shutting down: a watch would otherwise hold the shutdown until what it
// watches ends).
#pragma once

#include <atomic>

#include "insdiag/kb/fleet_store.h"
#include "insdiag/server/access_guard.h"
#include "insdiag/server/kb_services.h"
#include "insdiag/server/live_run_service.h"
#include "insdiag/server/run_service.h"
#include "insdiag/server/test_report_service.h"
#include "insdiag/v1/access.grpc.pb.h"
#include "insdiag/v1/analyses.grpc.pb.h"
#include "insdiag/v1/fleet.grpc.pb.h"
#include "insdiag/v1/knowledge.grpc.pb.h"
#include "insdiag/v1/live.grpc.pb.h"
#include "insdiag/v1/runs.grpc.pb.h"

namespace insdiag::server {

class RunServiceGrpc final : public v1::RunService::Service {
 public:
  RunServiceGrpc(RunService& runs, AccessGuard& guard) : runs_(runs), guard_(guard) {}

  grpc::Status UploadRun(grpc::ServerContext* context, grpc::ServerReader<v1::UploadRunRequest>* reader,
                         v1::Run* response) override;
  grpc::Status GetRun(grpc::ServerContext* context, const v1::GetRunRequest* request,
                      v1::Run* response) override;
  grpc::Status ListRuns(grpc::ServerContext* context, const v1::ListRunsRequest* request,
                        v1::ListRunsResponse* response) override;
  grpc::Status DeleteRun(grpc::ServerContext* context, const v1::DeleteRunRequest* request,
                         google::protobuf::Empty* response) override;
  grpc::Status ReadRunSamples(grpc::ServerContext* context, const v1::ReadRunSamplesRequest* request,
                              grpc::ServerWriter<v1::SampleChunk>* writer) override;

 private:
  RunService& runs_;
  AccessGuard& guard_;
};

class LiveRunServiceGrpc final : public v1::LiveRunService::Service {
 public:
  LiveRunServiceGrpc(LiveRunService& live, AccessGuard& guard, const std::atomic<bool>& stopping)
      : live_(live), guard_(guard), stopping_(stopping) {}

  grpc::Status MonitorRun(grpc::ServerContext* context,
                          grpc::ServerReaderWriter<v1::LiveRun, v1::MonitorRunRequest>* stream) override;
  grpc::Status ListLiveRuns(grpc::ServerContext* context, const v1::ListLiveRunsRequest* request,
                            v1::ListLiveRunsResponse* response) override;
  grpc::Status WatchLiveRun(grpc::ServerContext* context, const v1::WatchLiveRunRequest* request,
                            grpc::ServerWriter<v1::LiveRun>* writer) override;

 private:
  LiveRunService& live_;
  AccessGuard& guard_;
  const std::atomic<bool>& stopping_;
};

// Declares a unary method `Name(Request) → Response` of a gRPC service base.
#define INSDIAG_UNARY(Name, Request, Response)                                             \
  grpc::Status Name(grpc::ServerContext* context, const v1::Request* request, v1::Response* response) override

class AnalysisServiceGrpc final : public v1::AnalysisService::Service {
 public:
  AnalysisServiceGrpc(AnalysisService& analyses, TestReportService& test_reports, AccessGuard& guard,
                      const std::atomic<bool>& stopping)
      : analyses_(analyses), test_reports_(test_reports), guard_(guard), stopping_(stopping) {}
  INSDIAG_UNARY(CreateAnalysis, CreateAnalysisRequest, Analysis);
  INSDIAG_UNARY(GetAnalysis, GetAnalysisRequest, Analysis);
  INSDIAG_UNARY(ListAnalyses, ListAnalysesRequest, ListAnalysesResponse);
  INSDIAG_UNARY(CancelAnalysis, CancelAnalysisRequest, Analysis);
  INSDIAG_UNARY(ReadDisplaySeries, ReadDisplaySeriesRequest, DisplaySeries);
  grpc::Status WatchAnalysis(grpc::ServerContext* context, const v1::WatchAnalysisRequest* request,
                             grpc::ServerWriter<v1::Analysis>* writer) override;
  grpc::Status ReadResidualSeries(grpc::ServerContext* context, const v1::ReadResidualSeriesRequest* request,
                                  grpc::ServerWriter<v1::ResidualSeriesChunk>* writer) override;
  grpc::Status GetTestReport(grpc::ServerContext* context, const v1::GetTestReportRequest* request,
                             google::api::HttpBody* response) override;

 private:
  AnalysisService& analyses_;
  TestReportService& test_reports_;
  AccessGuard& guard_;
  const std::atomic<bool>& stopping_;
};

class KnowledgeServiceGrpc final : public v1::KnowledgeService::Service {
 public:
  KnowledgeServiceGrpc(KnowledgeService& knowledge, AccessGuard& guard) : knowledge_(knowledge), guard_(guard) {}
  INSDIAG_UNARY(GetUnitType, GetUnitTypeRequest, UnitType);
  INSDIAG_UNARY(ListUnitTypes, ListUnitTypesRequest, ListUnitTypesResponse);
  INSDIAG_UNARY(GetUnit, GetUnitRequest, Unit);
  INSDIAG_UNARY(ListUnits, ListUnitsRequest, ListUnitsResponse);
  INSDIAG_UNARY(ListModules, ListModulesRequest, ListModulesResponse);
  INSDIAG_UNARY(GetUnitHistory, GetUnitHistoryRequest, UnitHistory);
  INSDIAG_UNARY(ListFailureModes, ListFailureModesRequest, ListFailureModesResponse);
  INSDIAG_UNARY(GetFailureMode, GetFailureModeRequest, FailureMode);
  INSDIAG_UNARY(CreateFailureRecord, CreateFailureRecordRequest, FailureRecord);
  INSDIAG_UNARY(CorrectFailureRecord, CorrectFailureRecordRequest, FailureRecord);
  INSDIAG_UNARY(ListFailureRecordRevisions, ListFailureRecordRevisionsRequest, ListFailureRecordRevisionsResponse);
  INSDIAG_UNARY(ListFailureRecords, ListFailureRecordsRequest, ListFailureRecordsResponse);
  INSDIAG_UNARY(CreateDiagnosis, CreateDiagnosisRequest, Diagnosis);
  INSDIAG_UNARY(GetDiagnosis, GetDiagnosisRequest, Diagnosis);
  INSDIAG_UNARY(ListDiagnoses, ListDiagnosesRequest, ListDiagnosesResponse);
  INSDIAG_UNARY(ResolveDiagnosis, ResolveDiagnosisRequest, Diagnosis);

 private:
  KnowledgeService& knowledge_;
  AccessGuard& guard_;
};

class FleetServiceGrpc final : public v1::FleetService::Service {
 public:
  FleetServiceGrpc(kb::FleetStore& fleet, AccessGuard& guard) : fleet_(fleet), guard_(guard) {}
  INSDIAG_UNARY(GetFleetStatistics, GetFleetStatisticsRequest, FleetStatistics);
  INSDIAG_UNARY(ListFailureCounts, ListFailureCountsRequest, ListFailureCountsResponse);
  INSDIAG_UNARY(GetFailurePareto, GetFailureParetoRequest, FailurePareto);
  INSDIAG_UNARY(GetWeibullFit, GetWeibullFitRequest, WeibullFit);
  INSDIAG_UNARY(ListParameterTrends, ListParameterTrendsRequest, ListParameterTrendsResponse);
  INSDIAG_UNARY(GetParameterTrend, GetParameterTrendRequest, ParameterTrend);
  INSDIAG_UNARY(RankUnits, RankUnitsRequest, RankUnitsResponse);

 private:
  kb::FleetStore& fleet_;
  AccessGuard& guard_;
};

class AccessServiceGrpc final : public v1::AccessService::Service {
 public:
  AccessServiceGrpc(AccessService& access, AccessGuard& guard) : access_(access), guard_(guard) {}
  INSDIAG_UNARY(GetCaller, GetCallerRequest, Caller);
  INSDIAG_UNARY(CreateToken, CreateTokenRequest, CreatedToken);
  INSDIAG_UNARY(ListTokens, ListTokensRequest, ListTokensResponse);
  INSDIAG_UNARY(RevokeToken, RevokeTokenRequest, Token);
  INSDIAG_UNARY(ListAuditEvents, ListAuditEventsRequest, ListAuditEventsResponse);

 private:
  AccessService& access_;
  AccessGuard& guard_;
};

#undef INSDIAG_UNARY

}  // namespace insdiag::server
