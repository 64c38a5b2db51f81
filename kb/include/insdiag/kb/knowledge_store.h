// The knowledge base's stores: unit types, units and modules, failure modes,
// failure records (the refusals database) and diagnoses
// (migrations/0002_knowledge.sql; the ranking math is kb/diagnosis.h).
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <span>
#include <string>
#include <vector>

#include "insdiag/kb/connection_pool.h"
#include "insdiag/kb/diagnosis.h"
#include "insdiag/v1/knowledge.pb.h"

namespace insdiag::kb {

struct PageQuery {
  int page_size = 50;
  std::string page_token;
};

class KnowledgeStore {
 public:
  explicit KnowledgeStore(ConnectionPool& pool) : pool_(pool) {}

  // Upserts the unit types, their nominal values and their failure modes
  // (expanded templates), idempotently and under an advisory lock: replicas
  // starting together seed once. A mode's refined signature is kept unless
  // the expert's values changed.
  absl::Status Seed(std::span<const v1::UnitType> unit_types, std::span<const v1::FailureModeCatalogue> catalogues);

  absl::StatusOr<v1::UnitType> GetUnitType(const std::string& name);  // unitTypes/{t}
  absl::StatusOr<std::vector<v1::UnitType>> ListUnitTypes();
  absl::StatusOr<v1::Unit> GetUnit(const std::string& name);  // units/{serial}
  absl::StatusOr<std::pair<std::vector<v1::Unit>, std::string>> ListUnits(const PageQuery& page,
                                                                          const std::string& unit_type,
                                                                          const std::string& batch);
  // Installation history, by role then installation.
  absl::StatusOr<std::vector<v1::Module>> ListModules(const std::string& unit_name);

  absl::StatusOr<v1::FailureMode> GetFailureMode(const std::string& name);
  absl::StatusOr<std::vector<v1::FailureMode>> ListFailureModes(const std::string& unit_type,
                                                                const std::string& module_role);

  // INVALID_ARGUMENT naming the field for a malformed record; NOT_FOUND for
  // an unknown module, mode or analysis.
  // The record takes `facts` (see CorrectFailureRecordRequest), and the
  // version it replaces is kept with `reason`, in one transaction; confirmed
  // modes it leaves or joins are refined again.
  absl::StatusOr<v1::FailureRecord> CorrectFailureRecord(const std::string& name, const v1::FailureRecord& facts,
                                                         const std::string& reason);
  absl::StatusOr<std::vector<v1::FailureRecordRevision>> ListFailureRecordRevisions(const std::string& name);
  absl::StatusOr<v1::FailureRecord> CreateFailureRecord(const v1::FailureRecord& record);
  struct RecordQuery {
    PageQuery page;
    std::string module;  // units/{u}/modules/{role}
    std::string unit;    // units/{u}
    std::string failure_mode;
  };
  absl::StatusOr<std::pair<std::vector<v1::FailureRecord>, std::string>> ListFailureRecords(const RecordQuery& query);

  // Diagnoses a SUCCEEDED analysis against its unit type's failure modes and
  // stores the result. FAILED_PRECONDITION when the analysis has not
  // succeeded or its unit has no known unit type.
  absl::StatusOr<v1::Diagnosis> CreateDiagnosis(const std::string& analysis_name);
  absl::StatusOr<v1::Diagnosis> GetDiagnosis(const std::string& name);
  struct DiagnosisQuery {
    PageQuery page;
    std::string analysis;
    std::string unit;
  };
  absl::StatusOr<std::pair<std::vector<v1::Diagnosis>, std::string>> ListDiagnoses(const DiagnosisQuery& query);
  // Writes the failure record (confirmed, or no fault found) and, when
  // confirmed, refines the mode's signature with the confirmed cases.
  // FAILED_PRECONDITION when already resolved.
  absl::StatusOr<v1::Diagnosis> ResolveDiagnosis(const v1::ResolveDiagnosisRequest& request);

  // Re-derives the signatures of the failure modes with confirmed cases (of
  // one unit type, or all when empty) from those cases, as confirming each
  // would have: after a bulk load such as the fleet generator's.
  absl::Status RefineSignatures(const std::string& unit_type);

 private:
  ConnectionPool& pool_;
};

}  // namespace insdiag::kb
