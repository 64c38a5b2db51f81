#include "insdiag/server/test_report_service.h"

#include <absl/strings/ascii.h>
#include <absl/strings/str_cat.h>
#include <absl/time/clock.h>
#include <absl/time/time.h>

#include "insdiag/api/resource_names.h"
#include "insdiag/engine/status_macros.h"
#include "insdiag/testreport/test_report.h"

namespace insdiag::server {

absl::StatusOr<google::api::HttpBody> TestReportService::GetTestReport(const v1::GetTestReportRequest& request) {
  const std::string format = absl::AsciiStrToLower(request.format());
  if (!format.empty() && format != "html" && format != "pdf") {
    return absl::InvalidArgumentError(absl::StrCat("format must be html or pdf, not '", request.format(), "'"));
  }
  v1::GetAnalysisRequest get;
  get.set_name(request.name());
  auto analysis = analyses_.GetAnalysis(get);
  if (!analysis.ok()) return analysis.status();
  if (analysis->state() != v1::Analysis::SUCCEEDED) {
    return absl::FailedPreconditionError(absl::StrCat(analysis->name(), " is ",
                                                      v1::Analysis::State_Name(analysis->state()),
                                                      ": only a SUCCEEDED analysis has a test report"));
  }
  testreport::TestReportInput input;
  v1::GetRunRequest run;
  run.set_name(analysis->run());
  INSDIAG_ASSIGN_OR_RETURN(auto stored_run, runs_.GetRun(run));
  input.run = std::move(stored_run);
  auto diagnosis = DiagnosisOf(request);
  if (!diagnosis.ok()) return diagnosis.status();
  input.diagnosis = std::move(*diagnosis);
  auto unit_type = UnitTypeOf(input.run);
  if (!unit_type.ok()) return unit_type.status();
  input.unit_type = std::move(*unit_type);
  v1::ReadDisplaySeriesRequest series;
  series.set_name(analysis->name());
  series.set_columns(options_.plot_columns);
  auto residuals = analyses_.ReadDisplaySeries(series);
  if (!residuals.ok()) return residuals.status();
  input.residuals = std::move(*residuals);
  input.analysis = std::move(*analysis);
  input.generated_at = absl::FormatTime("%Y-%m-%dT%H:%M:%SZ", absl::Now(), absl::UTCTimeZone());

  const testreport::Document document = testreport::BuildTestReport(input);
  google::api::HttpBody body;
  if (format == "pdf") {
    body.set_content_type("application/pdf");
    body.set_data(testreport::RenderPdf(document));
  } else {
    body.set_content_type("text/html; charset=utf-8");
    body.set_data(testreport::RenderHtml(document));
  }
  return body;
}

absl::StatusOr<std::optional<v1::Diagnosis>> TestReportService::DiagnosisOf(const v1::GetTestReportRequest& request) {
  if (!request.diagnosis().empty()) {
    v1::GetDiagnosisRequest get;
    get.set_name(request.diagnosis());
    INSDIAG_ASSIGN_OR_RETURN(auto diagnosis, knowledge_.GetDiagnosis(get));
    if (diagnosis.analysis() != request.name()) {
      return absl::InvalidArgumentError(absl::StrCat("diagnosis ", request.diagnosis(), " is of ",
                                                     diagnosis.analysis(), ", not of ",
                                                     request.name()));
    }
    return std::optional<v1::Diagnosis>(std::move(diagnosis));
  }
  v1::ListDiagnosesRequest list;  // newest first
  list.set_analysis(request.name());
  list.set_page_size(1);
  INSDIAG_ASSIGN_OR_RETURN(auto listed, knowledge_.ListDiagnoses(list));
  if (listed.diagnoses().empty()) return std::optional<v1::Diagnosis>();
  return std::optional<v1::Diagnosis>(listed.diagnoses(0));
}

absl::StatusOr<std::optional<v1::UnitType>> TestReportService::UnitTypeOf(const v1::Run& run) {
  if (run.metadata().unit_type().empty()) return std::optional<v1::UnitType>();
  v1::GetUnitTypeRequest get;
  get.set_name(api::ResourceName(api::kUnitTypes, run.metadata().unit_type()));
  auto unit_type = knowledge_.GetUnitType(get);
  // A type the knowledge base does not know has no nominal values: the
  // report then says so rather than failing.
  if (absl::IsNotFound(unit_type.status())) return std::optional<v1::UnitType>();
  if (!unit_type.ok()) return unit_type.status();
  return std::optional<v1::UnitType>(std::move(*unit_type));
}

}  // namespace insdiag::server
