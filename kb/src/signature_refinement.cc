#include "signature_refinement.h"

#include <vector>

#include "catalogue_rows.h"
#include "insdiag/engine/status_macros.h"
#include "insdiag/kb/diagnosis.h"
#include "report_rows.h"

namespace insdiag::kb::internal {

absl::Status RefineModeSignature(Connection& db, const std::string& mode_id, const ReportDecoder& decode_report) {
  INSDIAG_ASSIGN_OR_RETURN(auto modes, LoadModes(db, "", "", mode_id));
  if (modes.empty()) return absl::OkStatus();
  const FailureMode& mode = modes.front();
  const std::string type_id = UnitTypeId(mode.unit_type);
  INSDIAG_ASSIGN_OR_RETURN(auto unit_type, LoadUnitType(db, type_id));
  INSDIAG_ASSIGN_OR_RETURN(auto type_settings, SettingsFor(db, type_id));
  const DiagnosisSettings& settings = type_settings.settings;
  INSDIAG_ASSIGN_OR_RETURN(auto cases,
                           db.Exec("SELECT DISTINCT analysis_id::text FROM failure_records WHERE "
                                   "failure_mode = $1 AND confirmed "
                                   "AND analysis_id IS NOT NULL",
                                   {Param::Text(mode_id)}));
  std::vector<Evidence> evidence;
  for (int r = 0; r < cases.rows(); ++r) {
    auto report = LoadReport(db, cases.String(r, 0));
    if (!report.ok()) continue;  // a case whose analysis is gone no longer refines
    auto findings = ReportFindingsOf(*report, decode_report);
    if (!findings.ok()) continue;
    evidence.push_back(EvidenceFromReport(*findings, unit_type, settings));
  }
  for (int position = 0; position < static_cast<int>(mode.signature.size()); ++position) {
    const Signature& term = mode.signature[static_cast<std::size_t>(position)];
    std::vector<double> values;
    for (const auto& e : evidence) {
      if (auto v = CaseValue(term, e)) values.push_back(*v);
    }
    const Signature refined = RefineSignature(term, values, settings);
    INSDIAG_ASSIGN_OR_RETURN(
        auto updated,
        db.Exec("UPDATE signature_terms SET change = $3, spread = $4, confirmed_cases = $5 WHERE "
                "failure_mode = $1 AND "
                "position = $2",
                {Param::Text(mode_id), Param::Int(position), Param::Double(refined.change),
                 Param::Double(refined.spread), Param::Int(refined.confirmed_cases)}));
  }
  return db.Exec("UPDATE failure_modes SET update_time = now() WHERE failure_mode = $1", {Param::Text(mode_id)})
      .status();
}

}  // namespace insdiag::kb::internal
