// The test report of one analysis: the self-contained document a quality
// department files for a unit's bench test. It states the unit and the run,
// the verdict and the tolerances it was judged against (the seed's γ² on
// each β² = ν²/α², η² on the moving-window F, the χ² band of the mean NIS),
// the identified parameters beside the unit type's nominal values with
// their 95 % intervals (value ± 1.96 SE) and tolerances, the effects the
// analysis found, the diagnosis when there is one, and the key plots: each
// channel's residual inside its ±3σ band with the fault intervals shaded,
// and the Allan deviations.
//
// Built from the API's messages only, so that whoever holds them (the
// server; a client that fetched them) makes the same document.
#pragma once

#include <optional>
#include <string>

#include "insdiag/testreport/document.h"
#include "insdiag/v1/analyses.pb.h"
#include "insdiag/v1/knowledge.pb.h"
#include "insdiag/v1/runs.pb.h"

namespace insdiag::testreport {

struct TestReportInput {
  v1::Analysis analysis;  // SUCCEEDED: its report is the document's substance
  v1::Run run;            // the analysed run (metadata; no samples)
  std::optional<v1::Diagnosis> diagnosis;  // of this analysis, when one was made
  std::optional<v1::UnitType> unit_type;   // the run's unit type, for nominal values and tolerances
  v1::DisplaySeries residuals;             // the residual series decimated for plotting; may be empty
  std::string generated_at;                // RFC 3339 UTC, printed on the document
};

Document BuildTestReport(const TestReportInput& input);

// Self-contained HTML5: inline CSS and SVG, no script, no external resource.
std::string RenderHtml(const Document& document);

// PDF 1.4, A4 portrait (pdf_writer.h).
std::string RenderPdf(const Document& document);

}  // namespace insdiag::testreport
