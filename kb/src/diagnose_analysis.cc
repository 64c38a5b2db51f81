#include "insdiag/kb/diagnose_analysis.h"

#include "insdiag/api/resource_names.h"
#include "insdiag/engine/status_macros.h"
#include "insdiag/kb/diagnosis.h"

namespace insdiag::kb {

Diagnosis DiagnoseInputs(const DiagnosisInputs& in) {
  Evidence observed = EvidenceFromReport(in.report, in.unit_type, in.settings);
  if (!in.history_note.empty()) observed.notes.push_back(in.history_note);
  for (const EvidenceTerm& t : in.history_trends) observed.terms.push_back(t);
  if (!in.settings_note.empty()) observed.notes.push_back(in.settings_note);
  Diagnosis diagnosis = Diagnose(observed, in.modes, in.settings, in.prior);
  diagnosis.analysis = in.analysis_name;
  diagnosis.unit = api::ResourceName(api::kUnits, in.serial);
  return diagnosis;
}

absl::StatusOr<StoredDiagnosis> AnalysisDiagnoser::Diagnose(const std::string& analysis_name) {
  INSDIAG_ASSIGN_OR_RETURN(const DiagnosisInputs inputs, store_.LoadInputs(analysis_name));
  return store_.Store(inputs, DiagnoseInputs(inputs), encode_);
}

}  // namespace insdiag::kb
