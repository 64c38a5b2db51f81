// An analysis's report as the knowledge base holds it: the stored report
// bytes and, beside them, its queryable rows (kb/analysis.h, ReportRows),
// which are all there is of analyses stored without the bytes (the fleet
// generator writes only the rows).
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <string>

#include "insdiag/kb/analysis.h"
#include "insdiag/kb/pg.h"

namespace insdiag::kb::internal {

// The report of a SUCCEEDED analysis: its bytes when stored, else its rows.
// NOT_FOUND; FAILED_PRECONDITION when the analysis has not succeeded.
absl::StatusOr<StoredReport> LoadReport(Connection& db, const std::string& analysis_id);

// The analysis's rows: verdict and headline figures, identified parameters,
// effect candidates (per term and per family), channel metrics and fault
// intervals. NOT_FOUND.
absl::StatusOr<ReportRows> ReadReportRows(Connection& db, const std::string& analysis_id);

// Writes the rows beside the analysis (its verdict and headline figures are
// Complete's): channel metrics, identified parameters, candidates, fault
// intervals; figures that are not finite as 0.
absl::Status WriteReportRows(Connection& db, const std::string& analysis_id, const ReportRows& rows);

}  // namespace insdiag::kb::internal
