#include "insdiag/testreport/test_report.h"

#include <absl/strings/str_cat.h>

#include "sections.h"

namespace insdiag::testreport {

Document BuildTestReport(const TestReportInput& input) {
  const v1::AnalysisReport& report = input.analysis.report();
  const v1::RunMetadata& metadata = input.run.metadata();
  Document doc;
  doc.title = absl::StrCat("Test report: unit ", metadata.unit_serial());
  doc.subtitle = absl::StrCat(metadata.unit_type().empty() ? "" : metadata.unit_type() + ", ", input.analysis.name(),
                              " of ", input.run.name());
  doc.footer = absl::StrCat("insdiag test report, ", input.analysis.name(), ", generated ", input.generated_at);
  doc.generated_at = input.generated_at;
  doc.sections.push_back(VerdictSection(input));
  doc.sections.push_back(UnitAndRunSection(input));
  doc.sections.push_back(TolerancesSection(report));
  doc.sections.push_back(ParametersSection(report, input.unit_type));
  doc.sections.push_back(EffectsSection(report));
  doc.sections.push_back(DiagnosisSection(input.diagnosis));
  doc.sections.push_back(PlotsSection(report, input.residuals));
  if (!report.notes().empty()) {
    Section notes{"Notes of the analysis", {}};
    for (const auto& note : report.notes()) notes.blocks.push_back(Paragraph{note});
    doc.sections.push_back(std::move(notes));
  }
  return doc;
}

}  // namespace insdiag::testreport
