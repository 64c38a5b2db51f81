// An analysis's report as the knowledge base holds it: the stored report
// bytes, or — for analyses stored without them (the fleet generator writes
// only the queryable rows) — a report rebuilt from those rows.
#pragma once

#include <absl/status/statusor.h>

#include <string>

#include "insdiag/kb/pg.h"
#include "insdiag/v1/analyses.pb.h"

namespace insdiag::kb::internal {

// The report of a SUCCEEDED analysis (stored, else rebuilt). NOT_FOUND;
// FAILED_PRECONDITION when the analysis has not succeeded.
absl::StatusOr<v1::AnalysisReport> LoadReport(Connection& db, const std::string& analysis_id);

// A report rebuilt from the analysis's rows: verdict and headline figures,
// the model, identified parameters, effect candidates (per term and per
// family), channel metrics and fault intervals, with a note saying so.
absl::StatusOr<v1::AnalysisReport> RebuildReport(Connection& db, const std::string& analysis_id);

}  // namespace insdiag::kb::internal
