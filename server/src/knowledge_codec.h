// Units, modules, failure records and a diagnosis's resolution between the knowledge base's domain
// types (kb/knowledge.h, kb/failure_record.h) and their API form
// (insdiag.v1, knowledge.proto). The mapping sits here, at the API edge, so
// that the knowledge base never sees a protobuf message.
#pragma once

#include "insdiag/kb/diagnosis_store.h"
#include "insdiag/kb/failure_record.h"
#include "insdiag/kb/knowledge.h"
#include "insdiag/v1/knowledge.pb.h"

namespace insdiag::server {

// Unset commission_time and removed_time stay unset.
v1::Unit ToProto(const kb::Unit& unit);
v1::Module ToProto(const kb::Module& module);
// An unset detected_time stays unset.
v1::FailureRecord ToProto(const kb::FailureRecord& record);
v1::FailureRecordRevision ToProto(const kb::FailureRecordRevision& revision);

// An unset detected_time stays unset (a correction keeps the record's); an
// unset record_time reads as the Unix epoch, as in the message.
kb::FailureRecord FromProto(const v1::FailureRecord& record);

kb::DiagnosisResolution ResolutionOf(const v1::ResolveDiagnosisRequest& request);

}  // namespace insdiag::server
