// Engine values in and out of insdiag.v1 messages: the analysis report and
// the error model. The server, the CLI and the tests map them here, in one
// place, so that `insdiag analyze --json` and GetAnalysis print the same report.
#pragma once

#include <absl/status/statusor.h>

#include "insdiag/engine/model/error_model.h"
#include "insdiag/engine/report.h"
#include "insdiag/v1/analyses.pb.h"

namespace insdiag::api {

v1::AnalysisReport ToProto(const engine::AnalysisReport& report, const engine::ErrorModel& model);
v1::ErrorModel ToProto(const engine::ErrorModel& model);

// The series of one analysis as points, channel by channel and epoch by epoch.
v1::ResidualSeriesChunk ToProto(const engine::AnalysisSeries& series);

}  // namespace insdiag::api
