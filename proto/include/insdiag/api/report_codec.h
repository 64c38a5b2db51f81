// Engine values in and out of insdiag.v1 messages: the analysis report and
// the error model. The server, the CLI and the tests map them here, in one
// place, so that `insdiag analyze --json` and GetAnalysis print the same report.
#pragma once

#include <absl/status/statusor.h>

#include <optional>
#include <string>

#include "insdiag/engine/analysis.h"
#include "insdiag/engine/model/error_model.h"
#include "insdiag/engine/report.h"
#include "insdiag/v1/analyses.pb.h"

namespace insdiag::api {

v1::AnalysisReport ToProto(const engine::AnalysisReport& report, const engine::ErrorModel& model);
v1::ErrorModel ToProto(const engine::ErrorModel& model);
v1::AnalysisReport::Verdict ToProto(engine::Verdict verdict);
// The verdict a report states; nullopt for VERDICT_UNSPECIFIED (or a number the API does not define).
std::optional<engine::Verdict> VerdictOf(v1::AnalysisReport::Verdict verdict);
v1::FaultInterval ToProto(const engine::FaultInterval& interval);  // a non-finite statistic as 0

// Whether the run tells a parameter (engine::ObservableByRun), and why not:
// OBSERVABILITY_UNSPECIFIED (and no note) for an estimate that carries
// nothing to judge it by (other methods than the filter's constants).
struct Observability {
  v1::IdentifiedParameter::Observability verdict = v1::IdentifiedParameter::OBSERVABILITY_UNSPECIFIED;
  std::string note;  // empty when observable
};
Observability ObservabilityOf(const engine::ParameterEstimate& estimate);

// The model a report was computed with, as that analysis identified it, and
// the parameters it identified: what a later analysis of the same run starts
// from instead of identifying again. Refuses a parameter the engine does not
// know, naming it.
absl::StatusOr<engine::IdentifiedModel> IdentifiedModelOf(const v1::AnalysisReport& report);

// The series of one analysis as points, channel by channel and epoch by epoch.
v1::ResidualSeriesChunk ToProto(const engine::AnalysisSeries& series);

}  // namespace insdiag::api
