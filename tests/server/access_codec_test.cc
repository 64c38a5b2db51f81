#include "access_codec.h"

#include <gtest/gtest.h>

namespace insdiag::server {
namespace {

constexpr v1::Role kDefinedRoles[] = {v1::VIEWER, v1::OPERATOR, v1::ENGINEER, v1::ADMIN};

// The knowledge base stores a role by name; clients and the access rules name
// it by the API's enum. The two must agree, or a stored token changes role.
TEST(AccessCodec, EveryApiRoleKeepsItsNameAndNumber) {
  for (v1::Role role : kDefinedRoles) {
    EXPECT_EQ(kb::RoleName(RoleOf(role)), v1::Role_Name(role));
    EXPECT_EQ(kb::RoleFromName(v1::Role_Name(role)), RoleOf(role));
    EXPECT_EQ(ToProto(RoleOf(role)), role);
  }
  EXPECT_EQ(kb::RoleName(kb::Role::kUnspecified), v1::Role_Name(v1::ROLE_UNSPECIFIED));
  EXPECT_LT(RoleOf(v1::VIEWER), RoleOf(v1::OPERATOR));
  EXPECT_LT(RoleOf(v1::OPERATOR), RoleOf(v1::ENGINEER));
  EXPECT_LT(RoleOf(v1::ENGINEER), RoleOf(v1::ADMIN));
}

// Over gRPC a client may send any number as a role: it reads as no role,
// which CreateToken refuses.
TEST(AccessCodec, AnUndefinedRoleNumberIsNoRole) {
  EXPECT_EQ(RoleOf(static_cast<v1::Role>(9)), kb::Role::kUnspecified);
  EXPECT_EQ(RoleOf(v1::ROLE_UNSPECIFIED), kb::Role::kUnspecified);
}

TEST(AccessCodec, ATokenWithoutExpiryOrRevocationLeavesThemUnset) {
  kb::Token token;
  token.name = "tokens/0b0e8a4e-3a4b-4f43-9a54-6f0e2a1c9d10";
  token.display_name = "bench-3 uploader";
  token.role = kb::Role::kOperator;
  token.create_time = absl::FromUnixMicros(1'700'000'000'123'456);
  token.creator = "first start";
  const v1::Token message = ToProto(token);
  EXPECT_EQ(message.name(), token.name);
  EXPECT_EQ(message.display_name(), "bench-3 uploader");
  EXPECT_EQ(message.role(), v1::OPERATOR);
  EXPECT_EQ(message.create_time().seconds(), 1'700'000'000);
  EXPECT_EQ(message.create_time().nanos(), 123'456'000);
  EXPECT_FALSE(message.has_expire_time());
  EXPECT_FALSE(message.has_revoke_time());
  EXPECT_EQ(message.creator(), "first start");

  const kb::Token back = FromProto(message);
  EXPECT_EQ(back.create_time, token.create_time);
  EXPECT_FALSE(back.expire_time.has_value());
  EXPECT_FALSE(back.revoke_time.has_value());
}

TEST(AccessCodec, TimesKeepTheirNanosecondsEitherSideOfTheEpoch) {
  kb::Token token;
  token.create_time = absl::UnixEpoch();
  token.expire_time = absl::FromUnixNanos(1'800'000'000'987'654'321);
  token.revoke_time = absl::FromUnixMicros(-1);
  const v1::Token message = ToProto(token);
  EXPECT_TRUE(message.has_create_time());  // the epoch is a time, not "unset"
  EXPECT_EQ(message.expire_time().seconds(), 1'800'000'000);
  EXPECT_EQ(message.expire_time().nanos(), 987'654'321);
  EXPECT_EQ(message.revoke_time().seconds(), -1);  // nanos stay in [0, 1e9)
  EXPECT_EQ(message.revoke_time().nanos(), 999'999'000);

  const kb::Token back = FromProto(message);
  EXPECT_EQ(back.expire_time, token.expire_time);
  EXPECT_EQ(back.revoke_time, token.revoke_time);
}

TEST(AccessCodec, AnAuditEventWithoutACallerHasNoTokenAndNoRole) {
  kb::AuditEvent event;
  event.name = "auditEvents/42";
  event.event_time = absl::FromUnixSeconds(1'700'000'000);
  event.method = "insdiag.v1.RunService.DeleteRun";
  event.resource = "runs/r1";
  event.peer = "ipv4:10.0.0.7:51234";
  event.code = "UNAUTHENTICATED";
  event.message = "unknown bearer token";
  const v1::AuditEvent message = ToProto(event);
  EXPECT_EQ(message.name(), "auditEvents/42");
  EXPECT_EQ(message.event_time().seconds(), 1'700'000'000);
  EXPECT_TRUE(message.token().empty());
  EXPECT_EQ(message.role(), v1::ROLE_UNSPECIFIED);
  EXPECT_EQ(message.method(), event.method);
  EXPECT_EQ(message.resource(), "runs/r1");
  EXPECT_EQ(message.peer(), event.peer);
  EXPECT_EQ(message.code(), "UNAUTHENTICATED");
  EXPECT_EQ(message.message(), "unknown bearer token");
}

TEST(AccessCodec, ACreatedTokenAndACallerKeepEveryField) {
  kb::CreatedToken created;
  created.token.name = "tokens/0b0e8a4e-3a4b-4f43-9a54-6f0e2a1c9d10";
  created.token.role = kb::Role::kAdmin;
  created.secret = "insdiag_secret";
  const v1::CreatedToken message = ToProto(created);
  EXPECT_EQ(message.token().name(), created.token.name);
  EXPECT_EQ(message.token().role(), v1::ADMIN);
  EXPECT_EQ(message.secret(), "insdiag_secret");

  kb::Caller caller;
  caller.token = created.token.name;
  caller.display_name = "administrator (first start)";
  caller.role = kb::Role::kAdmin;
  const v1::Caller who = ToProto(caller);
  EXPECT_EQ(who.token(), caller.token);
  EXPECT_EQ(who.display_name(), caller.display_name);
  EXPECT_EQ(who.role(), v1::ADMIN);
}

}  // namespace
}  // namespace insdiag::server
