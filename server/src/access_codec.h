// Tokens, callers, roles and audit events between the knowledge base's
// domain types (kb/access_store.h) and their API form (insdiag.v1, access.proto).
// The mapping sits here, at the API edge, so that the knowledge base never
// sees a protobuf message.
#pragma once

#include "insdiag/kb/access_store.h"
#include "insdiag/v1/access.pb.h"

namespace insdiag::server {

// kUnspecified for ROLE_UNSPECIFIED and for a number insdiag.v1.Role does not
// define (a client may send any).
kb::Role RoleOf(v1::Role role);
v1::Role ToProto(kb::Role role);

v1::Caller ToProto(const kb::Caller& caller);
// Unset expire_time and revoke_time stay unset.
v1::Token ToProto(const kb::Token& token);
v1::CreatedToken ToProto(const kb::CreatedToken& created);
v1::AuditEvent ToProto(const kb::AuditEvent& event);

// An unset create_time reads as the Unix epoch, as in the message.
kb::Token FromProto(const v1::Token& token);

}  // namespace insdiag::server
