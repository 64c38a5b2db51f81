// The test report's sections, each from the messages it states
// (test_report.cc assembles them).
#pragma once

#include <optional>
#include <string>

#include "insdiag/testreport/document.h"
#include "insdiag/testreport/test_report.h"

namespace insdiag::testreport {

// Numbers as the report prints them: four significant digits.
std::string Num(double v);

Section VerdictSection(const TestReportInput& input);
Section UnitAndRunSection(const TestReportInput& input);
Section TolerancesSection(const v1::AnalysisReport& report);
Section ParametersSection(const v1::AnalysisReport& report, const std::optional<v1::UnitType>& unit_type);
Section EffectsSection(const v1::AnalysisReport& report);
Section DiagnosisSection(const std::optional<v1::Diagnosis>& diagnosis);
// Each channel's residual in its ±3σ band, fault intervals shaded; the Allan deviations.
Section PlotsSection(const v1::AnalysisReport& report, const v1::DisplaySeries& residuals);

}  // namespace insdiag::testreport
