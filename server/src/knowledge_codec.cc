#include "knowledge_codec.h"

#include "insdiag/api/time_codec.h"

namespace insdiag::server {

v1::Unit ToProto(const kb::Unit& unit) {
  v1::Unit message;
  message.set_name(unit.name);
  message.set_unit_type(unit.unit_type);
  message.set_operating_hours(unit.operating_hours);
  *message.mutable_create_time() = api::TimestampOf(unit.create_time);
  message.set_batch(unit.batch);
  if (unit.commission_time.has_value()) *message.mutable_commission_time() = api::TimestampOf(*unit.commission_time);
  message.set_retired(unit.retired);
  return message;
}

v1::Module ToProto(const kb::Module& module) {
  v1::Module message;
  message.set_name(module.name);
  message.set_role(module.role);
  message.set_part_serial(module.part_serial);
  *message.mutable_installed_time() = api::TimestampOf(module.installed_time);
  message.set_installed_hours(module.installed_hours);
  if (module.removed_time.has_value()) *message.mutable_removed_time() = api::TimestampOf(*module.removed_time);
  message.set_removed_hours(module.removed_hours);
  message.set_removal_reason(module.removal_reason);
  message.set_current(module.current);
  return message;
}

v1::FailureRecord ToProto(const kb::FailureRecord& record) {
  v1::FailureRecord message;
  message.set_name(record.name);
  message.set_module(record.module);
  message.set_failure_mode(record.failure_mode);
  message.set_analysis(record.analysis);
  message.set_operating_hours(record.operating_hours);
  message.set_confirmed(record.confirmed);
  message.set_repaired(record.repaired);
  message.set_censored(record.censored);
  *message.mutable_record_time() = api::TimestampOf(record.record_time);
  message.set_no_fault_found(record.no_fault_found);
  message.set_repair_action(record.repair_action);
  if (record.detected_time.has_value()) *message.mutable_detected_time() = api::TimestampOf(*record.detected_time);
  message.set_diagnosis(record.diagnosis);
  message.set_notes(record.notes);
  message.set_revision(record.revision);
  return message;
}

v1::FailureRecordRevision ToProto(const kb::FailureRecordRevision& revision) {
  v1::FailureRecordRevision message;
  *message.mutable_failure_record() = ToProto(revision.failure_record);
  *message.mutable_superseded_time() = api::TimestampOf(revision.superseded_time);
  message.set_reason(revision.reason);
  return message;
}

kb::FailureRecord FromProto(const v1::FailureRecord& record) {
  kb::FailureRecord domain;
  domain.name = record.name();
  domain.module = record.module();
  domain.failure_mode = record.failure_mode();
  domain.analysis = record.analysis();
  domain.diagnosis = record.diagnosis();
  domain.operating_hours = record.operating_hours();
  domain.confirmed = record.confirmed();
  domain.no_fault_found = record.no_fault_found();
  domain.censored = record.censored();
  domain.repaired = record.repaired();
  domain.repair_action = record.repair_action();
  domain.notes = record.notes();
  if (record.has_detected_time()) domain.detected_time = api::TimeOf(record.detected_time());
  domain.record_time = api::TimeOf(record.record_time());
  domain.revision = record.revision();
  return domain;
}

kb::DiagnosisResolution ResolutionOf(const v1::ResolveDiagnosisRequest& request) {
  kb::DiagnosisResolution resolution;
  resolution.name = request.name();
  resolution.module = request.module();
  resolution.failure_mode = request.failure_mode();
  resolution.confirmed = request.confirmed();
  resolution.repair_action = request.repair_action();
  resolution.notes = request.notes();
  return resolution;
}

}  // namespace insdiag::server
