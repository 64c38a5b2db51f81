// Bearer tokens and the audit trail (migrations/0004_access.sql). Their API
// form is proto/insdiag/v1/access.proto, which the server maps to and from.
//
// A token's secret is "insdiag_" followed by 43 base64url characters of 32
// random bytes (256 bits); only its SHA-256 is stored, so a stolen database
// does not hand out working tokens. With that much entropy a plain hash is
// enough: there is nothing to brute-force that a slow hash would protect.
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>
#include <absl/time/time.h>

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "insdiag/kb/connection_pool.h"
#include "insdiag/kb/page_query.h"

namespace insdiag::kb {

// Ordered: each role may do what the ones before it may, so a method's least
// role is checked with `<`.
enum class Role { kUnspecified, kViewer, kOperator, kEngineer, kAdmin };

// The role's name as stored ("OPERATOR"); "ROLE_UNSPECIFIED" for none.
std::string RoleName(Role role);
// The role a stored name stands for; kUnspecified for any other text.
Role RoleFromName(std::string_view name);

// The holder of a valid token.
struct Caller {
  std::string token;  // tokens/{token}
  std::string display_name;
  Role role = Role::kUnspecified;
};

struct Token {
  std::string name;          // tokens/{token}
  std::string display_name;  // who or what holds it, e.g. "bench-3 uploader"
  Role role = Role::kUnspecified;
  absl::Time create_time;
  std::optional<absl::Time> expire_time;  // none: never expires
  std::optional<absl::Time> revoke_time;  // none: not revoked
  std::string creator;                    // the token that created it, or "first start"
};

// A new token with its secret, which is stored nowhere.
struct CreatedToken {
  Token token;
  std::string secret;  // sent as "authorization: Bearer <secret>"
};

// One call of a writing method.
struct AuditEvent {
  std::string name;  // auditEvents/{event}
  absl::Time event_time;
  std::string token;         // tokens/{token}; empty when the caller had no valid token
  std::string display_name;  // the token's, at the time
  Role role = Role::kUnspecified;
  std::string method;    // insdiag.v1.RunService.DeleteRun
  std::string resource;  // the resource named or created, e.g. runs/…
  std::string peer;      // ipv4:10.0.0.7:51234
  std::string code;      // the outcome: OK, PERMISSION_DENIED, NOT_FOUND, …
  std::string message;   // the error message, when not OK
};

// Who made an audited call.
struct AuditedCall {
  std::optional<Caller> caller;  // absent: no valid token
  std::string method;                // insdiag.v1.RunService.DeleteRun
  std::string resource;              // runs/…
  std::string peer;
  absl::Status outcome;
};

struct AuditQuery {
  PageQuery page;
  std::string resource;  // only this resource when not empty
  std::string token;     // only this token (tokens/{token}) when not empty
};

class AccessStore {
 public:
  explicit AccessStore(ConnectionPool& pool) : pool_(pool) {}

  // The caller a secret belongs to. UNAUTHENTICATED, saying why, for an
  // unknown, revoked or expired token.
  absl::StatusOr<Caller> Authenticate(const std::string& secret);

  // A new token and its secret, from `token`'s display name, role and
  // expiry (its other fields are the store's to set). INVALID_ARGUMENT for an
  // empty display name, no role, or an expiry not in the future. `creator`:
  // tokens/{token} of the caller.
  absl::StatusOr<CreatedToken> CreateToken(const Token& token, const std::string& creator);
  absl::StatusOr<std::pair<std::vector<Token>, std::string>> ListTokens(const PageQuery& page);
  // NOT_FOUND for an unknown token; revoking twice keeps the first time.
  absl::StatusOr<Token> RevokeToken(const std::string& name);

  // On a database without any token: an ADMIN token whose secret is written
  // to `secret_file` (mode 0600) before the token is stored, so that a token
  // never exists that nobody can read. Returns true when it made one. Safe
  // when several servers start on one database at once.
  absl::StatusOr<bool> CreateFirstAdminToken(const std::filesystem::path& secret_file);

  absl::Status RecordAuditEvent(const AuditedCall& call);
  absl::StatusOr<std::pair<std::vector<AuditEvent>, std::string>> ListAuditEvents(const AuditQuery& query);

 private:
  ConnectionPool& pool_;
};

}  // namespace insdiag::kb
