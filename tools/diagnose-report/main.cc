// insdiag-diagnose-report — diagnoses a saved analysis report offline, with
// no server and no knowledge base: the report's evidence against a built-in
// unit type's nominal values and failure modes (insdiag/kb/diagnosis.h,
// docs/DIAGNOSIS.md), at the expert priors (no fleet counts, no unit
// history). For re-reading archived reports, and for the diagnosis sweeps,
// which keep their reports and diagnose them again when the failure modes
// change. Prints the diagnosis as JSON (insdiag.v1.Diagnosis).
// Exit status: 0 ok, 1 refused or failed, 2 bad usage.
#include <CLI/CLI.hpp>
#include <absl/strings/str_cat.h>

#include <fstream>
#include <iostream>
#include <sstream>

#include "insdiag/api/json.h"
#include "insdiag/kb/catalogue_data.h"
#include "insdiag/kb/diagnosis.h"
#include "insdiag/kb/knowledge_messages.h"

namespace {

int Fail(const std::string& what, const absl::Status& status) {
  std::cerr << "insdiag-diagnose-report: " << what << ": " << status.message() << "\n";
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"insdiag-diagnose-report — diagnose a saved analysis report (insdiag analyze --json) "
               "against a built-in unit type's failure modes, offline"};
  std::string report_path;
  std::string unit_type_name = "INS-2000";
  double exposure_hours = 0.0;
  app.add_option("REPORT.json", report_path, "The analysis report (insdiag.v1.AnalysisReport as JSON)")
      ->required();
  app.add_option("--unit-type", unit_type_name, "Built-in unit type whose nominal values and failure modes apply")
      ->capture_default_str();
  app.add_option("--exposure-hours", exposure_hours,
                 "The unit's operating hours since its previous analysis (default: the unit type's minimum "
                 "exposure)");
  CLI11_PARSE(app, argc, argv);

  std::ifstream in(report_path);
  if (!in) return Fail(report_path, absl::NotFoundError("cannot be read"));
  std::stringstream text;
  text << in.rdbuf();
  insdiag::v1::AnalysisReport report;
  if (auto parsed = insdiag::api::FromJson(text.str(), &report); !parsed.ok()) return Fail(report_path, parsed);

  namespace kb = insdiag::kb;
  auto catalogue = kb::BuiltinUnitTypeCatalogue(unit_type_name);
  if (!catalogue.ok()) {
    // A malformed built-in template is the build's fault, not the user's choice of unit type.
    return Fail(catalogue.status().code() == absl::StatusCode::kInvalidArgument ? "failure modes" : "--unit-type",
                catalogue.status());
  }
  kb::PriorInputs prior;
  prior.exposure_hours = exposure_hours;
  const kb::Diagnosis diagnosis =
      kb::Diagnose(kb::EvidenceFromReport(kb::FindingsOf(report), catalogue->unit_type, catalogue->settings),
                   catalogue->failure_modes, catalogue->settings, prior);
  auto json = insdiag::api::ToJson(kb::ToProto(diagnosis), /*pretty=*/true);
  if (!json.ok()) return Fail("diagnosis", json.status());
  std::cout << *json << "\n";
  return 0;
}
