// Bearer tokens and the audit trail (migrations/0004_access.sql,
// proto/insdiag/v1/access.proto).
//
// A token's secret is "insdiag_" followed by 43 base64url characters of 32
// random bytes (256 bits); only its SHA-256 is stored, so a stolen database
// does not hand out working tokens. With that much entropy a plain hash is
// enough: there is nothing to brute-force that a slow hash would protect.
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "insdiag/kb/connection_pool.h"
#include "insdiag/kb/page_query.h"
#include "insdiag/v1/access.pb.h"

namespace insdiag::kb {

// Who made an audited call.
struct AuditedCall {
  std::optional<v1::Caller> caller;  // absent: no valid token
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
  absl::StatusOr<v1::Caller> Authenticate(const std::string& secret);

  // A new token and its secret. INVALID_ARGUMENT for an empty display name,
  // no role, or an expiry not in the future. `creator`: tokens/{token} of the
  // caller.
  absl::StatusOr<v1::CreatedToken> CreateToken(const v1::Token& token, const std::string& creator);
  absl::StatusOr<std::pair<std::vector<v1::Token>, std::string>> ListTokens(const PageQuery& page);
  // NOT_FOUND for an unknown token; revoking twice keeps the first time.
  absl::StatusOr<v1::Token> RevokeToken(const std::string& name);

  // On a database without any token: an ADMIN token whose secret is written
  // to `secret_file` (mode 0600) before the token is stored, so that a token
  // never exists that nobody can read. Returns true when it made one. Safe
  // when several servers start on one database at once.
  absl::StatusOr<bool> CreateFirstAdminToken(const std::filesystem::path& secret_file);

  absl::Status RecordAuditEvent(const AuditedCall& call);
  absl::StatusOr<std::pair<std::vector<v1::AuditEvent>, std::string>> ListAuditEvents(const AuditQuery& query);

 private:
  ConnectionPool& pool_;
};

// The role's name as stored ("OPERATOR").
std::string RoleName(v1::Role role);

}  // namespace insdiag::kb
