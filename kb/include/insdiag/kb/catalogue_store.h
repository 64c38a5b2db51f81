// The knowledge base's catalogue: unit types with their nominal values,
// units and their modules, failure modes with their signatures
// (migrations/0002_knowledge.sql), each unit type's diagnosis settings
// (0006_diagnosis_settings.sql), and seeding them from the expert catalogues
// (read and expanded at the edge, insdiag/kb/catalogue_data.h).
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <span>
#include <string>
#include <utility>
#include <vector>

#include "insdiag/kb/connection_pool.h"
#include "insdiag/kb/knowledge.h"
#include "insdiag/kb/page_query.h"

namespace insdiag::kb {

class CatalogueStore {
 public:
  // `list_pool`: where the listings read (a streaming replica of the
  // database, the server's --read-database-url); null: `pool`.
  explicit CatalogueStore(ConnectionPool& pool, ConnectionPool* list_pool = nullptr)
      : pool_(pool), list_pool_(list_pool != nullptr ? *list_pool : pool) {}

  // Upserts the unit types, their nominal values, their failure modes
  // (expanded templates) and their diagnosis settings, idempotently and
  // under an advisory lock: replicas starting together seed once. A mode's
  // refined signature is kept unless the expert's values changed. Each mode's
  // and each settings' unit type is one of `unit_types` or already stored.
  absl::Status Seed(std::span<const UnitType> unit_types, std::span<const FailureMode> failure_modes,
                    std::span<const UnitTypeDiagnosisSettings> settings);

  absl::StatusOr<UnitType> GetUnitType(const std::string& name);  // unitTypes/{t}
  absl::StatusOr<std::vector<UnitType>> ListUnitTypes();
  absl::StatusOr<Unit> GetUnit(const std::string& name);  // units/{serial}
  // By serial; each filter (unitTypes/{t}, a batch) applies when not empty.
  absl::StatusOr<std::pair<std::vector<Unit>, std::string>> ListUnits(const PageQuery& page,
                                                                      const std::string& unit_type,
                                                                      const std::string& batch);
  // Installation history, by role then installation.
  absl::StatusOr<std::vector<Module>> ListModules(const std::string& unit_name);

  absl::StatusOr<FailureMode> GetFailureMode(const std::string& name);
  absl::StatusOr<std::vector<FailureMode>> ListFailureModes(const std::string& unit_type,
                                                                const std::string& module_role);

 private:
  ConnectionPool& pool_;
  ConnectionPool& list_pool_;
};

}  // namespace insdiag::kb
