// The methods of insdiag.v1.AnalysisService, KnowledgeService and
// AccessService, once, independent of transport: requests in, responses or
// absl::Status out, over the knowledge base's stores, each mapped at the
// call (the codecs in server/src). The gRPC face adapts them
// (grpc_services.h), and maps FleetService's over the fleet store itself;
// REST reaches them through gRPC (rest_gateway.h).
#pragma once

#include <absl/functional/function_ref.h>
#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <chrono>
#include <functional>

#include "insdiag/kb/access_store.h"
#include "insdiag/kb/analysis_store.h"
#include "insdiag/kb/catalogue_store.h"
#include "insdiag/kb/diagnosis_store.h"
#include "insdiag/kb/failure_record_store.h"
#include "insdiag/kb/unit_history_store.h"
#include "insdiag/v1/access.pb.h"
#include "insdiag/v1/analyses.pb.h"
#include "insdiag/v1/history.pb.h"
#include "insdiag/v1/knowledge.pb.h"

namespace insdiag::server {

class AnalysisService {
 public:
  struct Options {
    // WatchAnalysis polls the row this often: it sees jobs run by any
    // insdiagd on the database.
    std::chrono::milliseconds watch_poll{250};
    // Called once a job is queued: this process's idle workers take it now
    // rather than at their next poll (null: nothing to tell).
    std::function<void()> queued;
  };
  AnalysisService(kb::AnalysisStore& store, Options options) : store_(store), options_(options) {}

  absl::StatusOr<v1::Analysis> CreateAnalysis(const v1::CreateAnalysisRequest& request);
  absl::StatusOr<v1::Analysis> GetAnalysis(const v1::GetAnalysisRequest& request);
  absl::StatusOr<v1::ListAnalysesResponse> ListAnalyses(const v1::ListAnalysesRequest& request);
  absl::StatusOr<v1::Analysis> CancelAnalysis(const v1::CancelAnalysisRequest& request);
  // Calls `send` on every change until a terminal state, or until `send`
  // returns false or `stop()` is true (client gone, server stopping).
  absl::Status WatchAnalysis(const v1::WatchAnalysisRequest& request,
                             absl::FunctionRef<bool(const v1::Analysis&)> send, std::function<bool()> stop);
  absl::Status ReadResidualSeries(const v1::ReadResidualSeriesRequest& request,
                                  absl::FunctionRef<bool(const v1::ResidualSeriesChunk&)> send);
  // The series decimated for a plot (display_series.h).
  absl::StatusOr<v1::DisplaySeries> ReadDisplaySeries(const v1::ReadDisplaySeriesRequest& request);

 private:
  absl::Status CheckBaseAnalysis(const v1::Analysis& asked, v1::AnalysisSpec& spec);

  kb::AnalysisStore& store_;
  Options options_;
};

class KnowledgeService {
 public:
  KnowledgeService(kb::CatalogueStore& catalogue, kb::FailureRecordStore& records, kb::DiagnosisStore& diagnoses,
                   kb::UnitHistoryStore& history)
      : catalogue_(catalogue), records_(records), diagnoses_(diagnoses), history_(history) {}

  absl::StatusOr<v1::UnitType> GetUnitType(const v1::GetUnitTypeRequest& request);
  absl::StatusOr<v1::ListUnitTypesResponse> ListUnitTypes(const v1::ListUnitTypesRequest& request);
  absl::StatusOr<v1::Unit> GetUnit(const v1::GetUnitRequest& request);
  absl::StatusOr<v1::ListUnitsResponse> ListUnits(const v1::ListUnitsRequest& request);
  absl::StatusOr<v1::ListModulesResponse> ListModules(const v1::ListModulesRequest& request);
  absl::StatusOr<v1::UnitHistory> GetUnitHistory(const v1::GetUnitHistoryRequest& request);
  absl::StatusOr<v1::ListFailureModesResponse> ListFailureModes(const v1::ListFailureModesRequest& request);
  absl::StatusOr<v1::FailureMode> GetFailureMode(const v1::GetFailureModeRequest& request);
  absl::StatusOr<v1::FailureRecord> CreateFailureRecord(const v1::CreateFailureRecordRequest& request);
  absl::StatusOr<v1::FailureRecord> CorrectFailureRecord(const v1::CorrectFailureRecordRequest& request);
  absl::StatusOr<v1::ListFailureRecordRevisionsResponse> ListFailureRecordRevisions(
      const v1::ListFailureRecordRevisionsRequest& request);
  absl::StatusOr<v1::ListFailureRecordsResponse> ListFailureRecords(const v1::ListFailureRecordsRequest& request);
  absl::StatusOr<v1::Diagnosis> CreateDiagnosis(const v1::CreateDiagnosisRequest& request);
  absl::StatusOr<v1::Diagnosis> GetDiagnosis(const v1::GetDiagnosisRequest& request);
  absl::StatusOr<v1::ListDiagnosesResponse> ListDiagnoses(const v1::ListDiagnosesRequest& request);
  absl::StatusOr<v1::Diagnosis> ResolveDiagnosis(const v1::ResolveDiagnosisRequest& request);

 private:
  kb::CatalogueStore& catalogue_;
  kb::FailureRecordStore& records_;
  kb::DiagnosisStore& diagnoses_;
  kb::UnitHistoryStore& history_;
};

// Tokens and the audit trail. The caller comes from the access guard
// (access_guard.h), which has already checked the method's role.
class AccessService {
 public:
  explicit AccessService(kb::AccessStore& store) : store_(store) {}

  absl::StatusOr<v1::Caller> GetCaller(const v1::GetCallerRequest& request, const kb::Caller& caller);
  absl::StatusOr<v1::CreatedToken> CreateToken(const v1::CreateTokenRequest& request, const kb::Caller& caller);
  absl::StatusOr<v1::ListTokensResponse> ListTokens(const v1::ListTokensRequest& request, const kb::Caller& caller);
  absl::StatusOr<v1::Token> RevokeToken(const v1::RevokeTokenRequest& request, const kb::Caller& caller);
  absl::StatusOr<v1::ListAuditEventsResponse> ListAuditEvents(const v1::ListAuditEventsRequest& request,
                                                              const kb::Caller& caller);

 private:
  kb::AccessStore& store_;
};

}  // namespace insdiag::server
