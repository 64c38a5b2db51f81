// AnalysisService.GetTestReport, independent of transport: it gathers what
// the test report states through the other services — the analysis and its
// report, its run, its diagnosis, the run's unit type, the residual series
// decimated for the plots — and has insdiag::testreport set the document.
// The gRPC face adapts it (grpc_services.h); REST answers with the document
// itself (rest_gateway.h: a google.api.HttpBody response).
#pragma once

#include <absl/status/statusor.h>

#include <optional>

#include "google/api/httpbody.pb.h"
#include "insdiag/server/kb_services.h"
#include "insdiag/server/run_service.h"
#include "insdiag/v1/analyses.pb.h"

namespace insdiag::server {

class TestReportService {
 public:
  struct Options {
    // Pixel columns of the residual plots' decimation (ReadDisplaySeries):
    // a plot is about 500 pt wide on A4, and 400 columns keep each channel's
    // envelope finer than a printer's line while the file stays small.
    int plot_columns = 400;
  };
  TestReportService(AnalysisService& analyses, RunService& runs, KnowledgeService& knowledge, Options options)
      : analyses_(analyses), runs_(runs), knowledge_(knowledge), options_(options) {}

  // INVALID_ARGUMENT for a format other than html or pdf, or a diagnosis of
  // another analysis; NOT_FOUND for an unknown analysis or diagnosis;
  // FAILED_PRECONDITION for an analysis that has not succeeded.
  absl::StatusOr<google::api::HttpBody> GetTestReport(const v1::GetTestReportRequest& request);

 private:
  absl::StatusOr<std::optional<v1::Diagnosis>> DiagnosisOf(const v1::GetTestReportRequest& request);
  absl::StatusOr<std::optional<v1::UnitType>> UnitTypeOf(const v1::Run& run);

  AnalysisService& analyses_;
  RunService& runs_;
  KnowledgeService& knowledge_;
  Options options_;
};

}  // namespace insdiag::server
