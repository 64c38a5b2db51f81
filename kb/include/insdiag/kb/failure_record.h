// A failure record of the refusals database (FRACAS): what was found on a
// unit's module, and a version of it that a correction replaced. Recording a
// failure (kb/failure_record_store.h) and resolving a diagnosis
// (kb/diagnosis_store.h) write them; their API form is
// insdiag.v1.FailureRecord (proto/insdiag/v1/knowledge.proto).
#pragma once

#include <absl/time/time.h>

#include <optional>
#include <string>

namespace insdiag::kb {

struct FailureRecord {
  std::string name;          // failureRecords/{record}
  std::string module;        // units/{unit}/modules/{role}
  std::string failure_mode;  // failureModes/{failure_mode}; empty for censored and no-fault-found records
  std::string analysis;      // analyses/{analysis}, when found by one
  std::string diagnosis;     // diagnoses/{diagnosis}, when written by resolving one
  double operating_hours = 0.0;  // the unit's, when the failure was detected
  bool confirmed = false;        // the failure was confirmed on the bench
  bool no_fault_found = false;   // the suspected module showed no fault
  bool censored = false;         // the unit was withdrawn without failing (a suspension)
  bool repaired = false;
  std::string repair_action;  // "module replaced", "recalibrated"
  std::string notes;
  // Unset in a record to write: now for a new record, kept by a correction.
  // Always set in a record read back.
  std::optional<absl::Time> detected_time;
  absl::Time record_time;  // when this version was written
  int revision = 0;        // 1 as created; one more at each correction
};

// A version of a failure record that a correction replaced.
struct FailureRecordRevision {
  FailureRecord failure_record;  // as it was, with its revision number
  absl::Time superseded_time;
  std::string reason;  // the correction's
};

}  // namespace insdiag::kb
