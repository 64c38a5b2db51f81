#include "access_codec.h"

#include "insdiag/api/time_codec.h"

namespace insdiag::server {

kb::Role RoleOf(v1::Role role) {
  switch (role) {
    case v1::VIEWER:
      return kb::Role::kViewer;
    case v1::OPERATOR:
      return kb::Role::kOperator;
    case v1::ENGINEER:
      return kb::Role::kEngineer;
    case v1::ADMIN:
      return kb::Role::kAdmin;
    default:
      return kb::Role::kUnspecified;
  }
}

v1::Role ToProto(kb::Role role) {
  switch (role) {
    case kb::Role::kViewer:
      return v1::VIEWER;
    case kb::Role::kOperator:
      return v1::OPERATOR;
    case kb::Role::kEngineer:
      return v1::ENGINEER;
    case kb::Role::kAdmin:
      return v1::ADMIN;
    case kb::Role::kUnspecified:
      break;
  }
  return v1::ROLE_UNSPECIFIED;
}

v1::Caller ToProto(const kb::Caller& caller) {
  v1::Caller message;
  message.set_token(caller.token);
  message.set_display_name(caller.display_name);
  message.set_role(ToProto(caller.role));
  return message;
}

v1::Token ToProto(const kb::Token& token) {
  v1::Token message;
  message.set_name(token.name);
  message.set_display_name(token.display_name);
  message.set_role(ToProto(token.role));
  *message.mutable_create_time() = api::TimestampOf(token.create_time);
  if (token.expire_time.has_value()) *message.mutable_expire_time() = api::TimestampOf(*token.expire_time);
  if (token.revoke_time.has_value()) *message.mutable_revoke_time() = api::TimestampOf(*token.revoke_time);
  message.set_creator(token.creator);
  return message;
}

v1::CreatedToken ToProto(const kb::CreatedToken& created) {
  v1::CreatedToken message;
  *message.mutable_token() = ToProto(created.token);
  message.set_secret(created.secret);
  return message;
}

v1::AuditEvent ToProto(const kb::AuditEvent& event) {
  v1::AuditEvent message;
  message.set_name(event.name);
  *message.mutable_event_time() = api::TimestampOf(event.event_time);
  message.set_token(event.token);
  message.set_display_name(event.display_name);
  message.set_role(ToProto(event.role));
  message.set_method(event.method);
  message.set_resource(event.resource);
  message.set_peer(event.peer);
  message.set_code(event.code);
  message.set_message(event.message);
  return message;
}

kb::Token FromProto(const v1::Token& token) {
  kb::Token domain;
  domain.name = token.name();
  domain.display_name = token.display_name();
  domain.role = RoleOf(token.role());
  domain.create_time = api::TimeOf(token.create_time());
  if (token.has_expire_time()) domain.expire_time = api::TimeOf(token.expire_time());
  if (token.has_revoke_time()) domain.revoke_time = api::TimeOf(token.revoke_time());
  domain.creator = token.creator();
  return domain;
}

}  // namespace insdiag::server
