// Stored diagnoses: what diagnosing an analysis reads (its report, its unit
// type's failure modes, the fleet's priors, the unit's history) and the
// diagnosis stored; resolving a diagnosis into a failure record; and the
// failure modes' signatures learnt from the confirmed cases
// (migrations/0002_knowledge.sql). The diagnosis itself is made by
// AnalysisDiagnoser (kb/diagnose_analysis.h), its math in kb/diagnosis.h.
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>
#include <absl/time/time.h>

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "insdiag/kb/analysis.h"
#include "insdiag/kb/connection_pool.h"
#include "insdiag/kb/diagnosis.h"
#include "insdiag/kb/page_query.h"

namespace insdiag::kb {

// Diagnoses newest first; each filter applies when not empty.
struct DiagnosisQuery {
  PageQuery page;
  std::string analysis;  // analyses/{a}
  std::string unit;      // units/{u}
};

// A diagnosis as the knowledge base keeps it: its name, the diagnosis in
// the API's encoding (which kb keeps and hands back without reading), and
// how it was resolved (empty until it is).
struct StoredDiagnosis {
  std::string name;            // diagnoses/{diagnosis}
  std::string encoded;         // as the caller's encoder wrote it
  std::string failure_record;  // failureRecords/{record}, once resolved
  std::string resolved_module;
  bool confirmed = false;
};

// How a diagnosis was settled on the bench: the module found faulty (or
// suspected), the failure mode found, and whether the fault was confirmed
// (false: no fault found).
struct DiagnosisResolution {
  std::string name;  // diagnoses/{diagnosis}
  std::string module;
  std::string failure_mode;  // failureModes/{mode}; required when confirmed
  bool confirmed = false;
  std::string repair_action;
  std::string notes;
};

// Writes a diagnosis in the API's encoding, with the name and create time
// the store gives it.
using DiagnosisEncoder =
    std::function<std::string(const Diagnosis& diagnosis, const std::string& name, absl::Time create_time)>;

// What the knowledge base holds for diagnosing one analysis.
struct DiagnosisInputs {
  std::string analysis_name;  // analyses/{a}
  std::string analysis_id;
  std::string unit_id;
  std::string serial;
  ReportFindings report;
  UnitType unit_type;
  std::vector<FailureMode> modes;
  DiagnosisSettings settings;
  std::string settings_note;  // when the unit type's catalogue has none and a default's apply
  PriorInputs prior;
  // The unit's own significant trends up to this analysis, and what its
  // history showed ("" before three runs: no trend to test yet).
  std::vector<EvidenceTerm> history_trends;
  std::string history_note;
};

class DiagnosisStore {
 public:
  // `decode_report`: what the diagnosis reads of a stored report's bytes.
  // `list_pool`: where the listings read (a streaming replica of the
  // database, the server's --read-database-url); null: `pool`.
  DiagnosisStore(ConnectionPool& pool, ReportDecoder decode_report, ConnectionPool* list_pool = nullptr)
      : pool_(pool), list_pool_(list_pool != nullptr ? *list_pool : pool), decode_report_(std::move(decode_report)) {}

  // What diagnosing a SUCCEEDED analysis reads. NOT_FOUND for no such
  // analysis; FAILED_PRECONDITION when it has not succeeded or its unit has
  // no known unit type.
  absl::StatusOr<DiagnosisInputs> LoadInputs(const std::string& analysis_name);
  // Stores the diagnosis made from `inputs`, naming it and its create time
  // and keeping it as `encode` writes it.
  absl::StatusOr<StoredDiagnosis> Store(const DiagnosisInputs& inputs, const Diagnosis& diagnosis,
                                        const DiagnosisEncoder& encode);
  absl::StatusOr<StoredDiagnosis> Get(const std::string& name);
  absl::StatusOr<std::pair<std::vector<StoredDiagnosis>, std::string>> List(const DiagnosisQuery& query);
  // Writes the failure record (confirmed, or no fault found) and, when
  // confirmed, refines the mode's signature with the confirmed cases.
  // FAILED_PRECONDITION when already resolved; INVALID_ARGUMENT naming the
  // field for a resolution without a module, or confirmed without a mode.
  absl::StatusOr<StoredDiagnosis> Resolve(const DiagnosisResolution& resolution);

  // Re-derives the signatures of the failure modes with confirmed cases (of
  // one unit type, or all when empty) from those cases, as confirming each
  // would have: after a bulk load such as the fleet generator's.
  absl::Status RefineSignatures(const std::string& unit_type);

 private:
  ConnectionPool& pool_;
  ConnectionPool& list_pool_;
  ReportDecoder decode_report_;
};

}  // namespace insdiag::kb
