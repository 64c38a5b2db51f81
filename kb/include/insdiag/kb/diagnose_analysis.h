// The diagnosis use case: an analysis's unit ranked against its unit type's
// failure modes, from what the report tells, the fleet's priors and the
// unit's own history (the math: kb/diagnosis.h, docs/DIAGNOSIS.md), and
// stored. The store reads and writes; this decides.
#pragma once

#include <absl/status/statusor.h>

#include <string>
#include <utility>

#include "insdiag/kb/diagnosis_store.h"

namespace insdiag::kb {

// The evidence and the diagnosis of loaded inputs, free of SQL.
Diagnosis DiagnoseInputs(const DiagnosisInputs& inputs);

class AnalysisDiagnoser {
 public:
  // `encode` writes the diagnosis as it is kept (the API's encoding, at the edge).
  AnalysisDiagnoser(DiagnosisStore& store, DiagnosisEncoder encode) : store_(store), encode_(std::move(encode)) {}

  // Diagnoses a SUCCEEDED analysis (analyses/{a}) and stores the diagnosis.
  // NOT_FOUND, FAILED_PRECONDITION: as DiagnosisStore::LoadInputs.
  absl::StatusOr<StoredDiagnosis> Diagnose(const std::string& analysis_name);

 private:
  DiagnosisStore& store_;
  DiagnosisEncoder encode_;
};

}  // namespace insdiag::kb
