// The analysis report as text for a person at a terminal, and the per-epoch
// series as CSV for plotting (`insdiag analyze --series`).
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "insdiag/engine/report.h"
#include "insdiag/v1/analyses.pb.h"

namespace insdiag::cli {

// The verdict line, then the verdict in plain words (engine/plain_words.h):
// what a quality engineer reads first; the engine's notes stay last.
void PrintReport(const engine::AnalysisReport& report, std::ostream& out);

// Whether the run tells an identified parameter, as the text reports show it:
// "observable", "NOT observable: inseparable, only with acc_turn_on_bias.z
// (correlation +1.000)", …; empty when not judged (other methods, or a report
// stored before the field).
std::string ObservabilityText(v1::IdentifiedParameter::Observability verdict, const std::string& note);

// CSV: t, then per channel <ch>_measured, <ch>_predicted, <ch>_residual, <ch>_sigma3.
void WriteSeriesCsv(const engine::AnalysisSeries& series, std::ostream& out);

// CSV: state, lag_s, acf, band, error_acf, then one column per converged family's fit.
void WriteCorrelationCsv(const engine::AnalysisReport& report, std::ostream& out);

// CSV: channel, tau_s, adev, adev_low, adev_high, fitted (unit: rad/s or m/s^2).
void WriteAllanCsv(const engine::AnalysisReport& report, std::ostream& out);

}  // namespace insdiag::cli
