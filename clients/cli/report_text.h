// The analysis report as text for a person at a terminal, and the per-epoch
// series as CSV for plotting (`insdiag analyze --series`).
#pragma once

#include <ostream>

#include "insdiag/engine/report.h"

namespace insdiag::cli {

void PrintReport(const engine::AnalysisReport& report, std::ostream& out);

// CSV: t, then per channel <ch>_measured, <ch>_predicted, <ch>_residual, <ch>_sigma3.
void WriteSeriesCsv(const engine::AnalysisSeries& series, std::ostream& out);

// CSV: state, lag_s, acf, band, error_acf, then one column per converged family's fit.
void WriteCorrelationCsv(const engine::AnalysisReport& report, std::ostream& out);

// CSV: channel, tau_s, adev, adev_low, adev_high, fitted (unit: rad/s or m/s^2).
void WriteAllanCsv(const engine::AnalysisReport& report, std::ostream& out);

}  // namespace insdiag::cli
