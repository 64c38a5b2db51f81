// The analysis report as text for a person at a terminal, and the per-epoch
// series as CSV for plotting (`insdiag analyze --series`).
#pragma once

#include <ostream>

#include "insdiag/engine/report.h"

namespace insdiag::cli {

void PrintReport(const engine::AnalysisReport& report, std::ostream& out);

// CSV: t, then per channel <ch>_measured, <ch>_predicted, <ch>_residual, <ch>_sigma3.
void WriteSeriesCsv(const engine::AnalysisSeries& series, std::ostream& out);

}  // namespace insdiag::cli
