#include "insdiag/kb/access_store.h"

#include <absl/strings/escaping.h>
#include <absl/strings/match.h>
#include <absl/strings/str_cat.h>
#include <absl/strings/str_replace.h>
#include <absl/time/clock.h>
#include <absl/time/time.h>
#include <fcntl.h>
#include <openssl/rand.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <string_view>
#include <tuple>

#include "insdiag/api/limits.h"
#include "insdiag/api/resource_names.h"
#include "insdiag/api/sha256.h"
#include "insdiag/engine/status_macros.h"
#include "store_util.h"

namespace insdiag::kb {
namespace {

using internal::Micros;

constexpr char kSecretPrefix[] = "insdiag_";
constexpr int kSecretBytes = 32;

absl::StatusOr<std::string> NewSecret() {
  std::array<unsigned char, kSecretBytes> bytes{};
  if (RAND_bytes(bytes.data(), kSecretBytes) != 1) {
    return absl::InternalError("the system's random number generator failed");
  }
  return absl::StrCat(kSecretPrefix,
                      absl::WebSafeBase64Escape(std::string(reinterpret_cast<const char*>(bytes.data()), kSecretBytes)));
}

// The stored names, which are also the API's (insdiag.v1.Role), by Role.
constexpr std::array<std::string_view, 5> kRoleNames = {"ROLE_UNSPECIFIED", "VIEWER", "OPERATOR", "ENGINEER",
                                                        "ADMIN"};

const std::string kTokenColumns = absl::StrCat(
    "SELECT token_id::text, display_name, role, creator, ", Micros("create_time"), ", ", Micros("expire_time"), ", ",
    Micros("revoke_time"), " FROM access_tokens ");

Token TokenFromRow(const Result& rows, int r) {
  Token token;
  token.name = absl::StrCat("tokens/", rows.String(r, 0));
  token.display_name = rows.String(r, 1);
  token.role = RoleFromName(rows.Get(r, 2));
  token.creator = rows.String(r, 3);
  token.create_time = absl::FromUnixMicros(internal::IntOr0(rows, r, 4));
  if (!rows.IsNull(r, 5)) token.expire_time = absl::FromUnixMicros(internal::IntOr0(rows, r, 5));
  if (!rows.IsNull(r, 6)) token.revoke_time = absl::FromUnixMicros(internal::IntOr0(rows, r, 6));
  return token;
}

// Writes `text` to a new file readable by its owner only; replaces a file
// left by an earlier database.
absl::Status WriteOwnerOnlyFile(const std::filesystem::path& path, const std::string& text) {
  std::error_code ignored;
  std::filesystem::create_directories(path.parent_path(), ignored);
  const std::filesystem::path partial = path.string() + ".partial";
  std::filesystem::remove(partial, ignored);
  const int fd = ::open(partial.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) return absl::PermissionDeniedError(absl::StrCat("cannot create ", partial.string(), ": ", std::strerror(errno)));
  const bool written = ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size()) && ::fsync(fd) == 0;
  ::close(fd);
  if (!written) return absl::InternalError(absl::StrCat("cannot write ", partial.string(), ": ", std::strerror(errno)));
  std::filesystem::rename(partial, path, ignored);
  if (ignored) return absl::InternalError(absl::StrCat("cannot rename to ", path.string(), ": ", ignored.message()));
  return absl::OkStatus();
}

}  // namespace

std::string RoleName(Role role) {
  const auto index = static_cast<std::size_t>(role);
  return index < kRoleNames.size() ? std::string(kRoleNames[index]) : "";
}

Role RoleFromName(std::string_view name) {
  for (std::size_t i = 0; i < kRoleNames.size(); ++i) {
    if (kRoleNames[i] == name) return static_cast<Role>(i);
  }
  return Role::kUnspecified;
}

absl::StatusOr<Caller> AccessStore::Authenticate(const std::string& secret) {
  if (!absl::StartsWith(secret, kSecretPrefix)) {
    return absl::UnauthenticatedError("the bearer token is not an insdiag token (they start with insdiag_)");
  }
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows, db->Exec("SELECT token_id::text, display_name, role, revoke_time IS NOT NULL, "
                          "expire_time IS NOT NULL AND expire_time <= now() FROM access_tokens "
                          "WHERE secret_sha256 = $1",
                          {Param::Bytes(api::Sha256(secret))}));
  if (rows.rows() == 0) return absl::UnauthenticatedError("unknown bearer token");
  const std::string name = absl::StrCat("tokens/", rows.String(0, 0));
  if (rows.Bool(0, 3)) return absl::UnauthenticatedError(absl::StrCat(name, " has been revoked"));
  if (rows.Bool(0, 4)) return absl::UnauthenticatedError(absl::StrCat(name, " has expired"));
  Caller caller;
  caller.token = name;
  caller.display_name = rows.String(0, 1);
  caller.role = RoleFromName(rows.Get(0, 2));
  return caller;
}

namespace {

// An expiry in the future and at most api::kMaxTokenLifetimeDays ahead.
absl::Status CheckExpiry(absl::Time when) {
  const absl::Time now = absl::Now();
  if (when <= now) return absl::InvalidArgumentError("token.expire_time: must be in the future");
  if (when > now + absl::Hours(24 * api::kMaxTokenLifetimeDays)) {
    return absl::InvalidArgumentError(absl::StrCat("token.expire_time: ", absl::FormatTime(absl::RFC3339_sec, when, absl::UTCTimeZone()),
                                                   " is more than ", api::kMaxTokenLifetimeDays,
                                                   " days (ten years) ahead; a token lives at most that long"));
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<CreatedToken> AccessStore::CreateToken(const Token& token, const std::string& creator) {
  if (token.display_name.empty()) return absl::InvalidArgumentError("token.display_name: required");
  if (token.role < Role::kViewer || token.role > Role::kAdmin) {
    return absl::InvalidArgumentError("token.role: one of VIEWER, OPERATOR, ENGINEER, ADMIN");
  }
  if (token.expire_time.has_value()) INSDIAG_RETURN_IF_ERROR(CheckExpiry(*token.expire_time));
  INSDIAG_ASSIGN_OR_RETURN(auto secret, NewSecret());
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  auto rows =
      db->Exec(absl::StrCat("WITH made AS (INSERT INTO access_tokens (display_name, role, "
                            "secret_sha256, creator, expire_time) "
                            "SELECT $1, $2, $3, $4, $5::timestamptz WHERE $5::timestamptz IS NULL "
                            "OR $5::timestamptz > now() "
                            "RETURNING *) ",
                            absl::StrReplaceAll(kTokenColumns, {{"access_tokens", "made"}})),
               {Param::Text(token.display_name), Param::Text(RoleName(token.role)),
                Param::Bytes(api::Sha256(secret)), Param::Text(creator),
                token.expire_time.has_value() ? Param::Text(internal::TimeText(*token.expire_time)) : Param::Null()});
  if (!rows.ok()) return rows.status();
  if (rows->rows() == 0) return absl::InvalidArgumentError("token.expire_time: must be in the future");
  CreatedToken created;
  created.token = TokenFromRow(*rows, 0);
  created.secret = secret;
  return created;
}

absl::StatusOr<std::pair<std::vector<Token>, std::string>> AccessStore::ListTokens(const PageQuery& page) {
  const int size = internal::ClampPageSize(page.page_size);
  std::vector<Param> params = {Param::Int(size + 1)};
  INSDIAG_ASSIGN_OR_RETURN(const std::string after,
                           internal::KeysetAfter(page.page_token, {{Micros("create_time"), "bigint"}, {"token_id", "uuid"}},
                                                 internal::KeysetOrder::kNewestFirst, params));
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows, db->Exec(absl::StrCat(kTokenColumns, "WHERE ", after, " ORDER BY create_time DESC, token_id DESC LIMIT $1"),
                          params));
  std::vector<Token> tokens;
  const int shown = std::min(rows.rows(), size);
  for (int r = 0; r < shown; ++r) tokens.push_back(TokenFromRow(rows, r));
  std::string next;
  if (rows.rows() > size)
    next = internal::EncodeToken(rows.String(shown - 1, 4), rows.String(shown - 1, 0));
  return std::make_pair(std::move(tokens), next);
}

absl::StatusOr<Token> AccessStore::RevokeToken(const std::string& name) {
  INSDIAG_ASSIGN_OR_RETURN(auto id, internal::UuidOf(name, api::kTokens, "name"));
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows,
      db->Exec(absl::StrCat("WITH revoked AS (UPDATE access_tokens SET revoke_time = "
                            "coalesce(revoke_time, now()) "
                            "WHERE token_id = $1::uuid RETURNING *) ",
                            absl::StrReplaceAll(kTokenColumns, {{"access_tokens", "revoked"}})),
               {Param::Text(id)}));
  if (rows.rows() == 0) return absl::NotFoundError(absl::StrCat(name, " does not exist"));
  return TokenFromRow(rows, 0);
}

absl::StatusOr<bool> AccessStore::CreateFirstAdminToken(const std::filesystem::path& secret_file) {
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  bool made = false;
  const absl::Status status = db->InTransaction([&]() -> absl::Status {
    INSDIAG_RETURN_IF_ERROR(db->Exec("SELECT pg_advisory_xact_lock($1)",
                                     {Param::Int(AdvisoryLockKey("insdiag.first_admin"))}));
    INSDIAG_ASSIGN_OR_RETURN(auto any, db->Exec("SELECT 1 FROM access_tokens LIMIT 1"));
    if (any.rows() > 0) return absl::OkStatus();
    INSDIAG_ASSIGN_OR_RETURN(auto secret, NewSecret());
    INSDIAG_RETURN_IF_ERROR(WriteOwnerOnlyFile(secret_file, secret + "\n"));
    INSDIAG_RETURN_IF_ERROR(
        db->Exec("INSERT INTO access_tokens (display_name, role, secret_sha256, creator) VALUES "
                 "($1, 'ADMIN', $2, 'first start')",
                 {Param::Text("administrator (first start)"), Param::Bytes(api::Sha256(secret))}));
    made = true;
    return absl::OkStatus();
  });
  if (!status.ok()) return status;
  return made;
}

absl::Status AccessStore::RecordAuditEvent(const AuditedCall& call) {
  std::optional<std::string> token_id;
  if (call.caller.has_value()) {
    auto id = internal::UuidOf(call.caller->token, api::kTokens, "token");
    if (id.ok()) token_id = *id;
  }
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  return (db)
      ->Exec(
          "INSERT INTO audit_events (token_id, display_name, role, method, resource, peer, code, "
          "message) "
          "VALUES ($1::uuid, $2, $3, $4, $5, $6, $7, $8)",
          {token_id ? Param::Text(*token_id) : Param::Null(),
           Param::Text(call.caller ? call.caller->display_name : ""),
           Param::Text(call.caller ? RoleName(call.caller->role) : ""), Param::Text(call.method),
           Param::Text(call.resource), Param::Text(call.peer),
           Param::Text(absl::StatusCodeToString(call.outcome.code())),
           Param::Text(std::string(call.outcome.message()))})
      .status();
}

absl::StatusOr<std::pair<std::vector<AuditEvent>, std::string>> AccessStore::ListAuditEvents(
    const AuditQuery& query) {
  const int size = internal::ClampPageSize(query.page.page_size);
  std::optional<std::string> token_id;
  if (!query.token.empty()) {
    INSDIAG_ASSIGN_OR_RETURN(auto id, internal::UuidOf(query.token, api::kTokens, "token"));
    token_id = id;
  }
  std::vector<Param> params = {Param::Int(size + 1), Param::TextOrNull(query.resource),
                               token_id ? Param::Text(*token_id) : Param::Null()};
  INSDIAG_ASSIGN_OR_RETURN(const std::string after,
                           internal::KeysetAfter(query.page.page_token, {{"event_id", "bigint"}},
                                                 internal::KeysetOrder::kDescending, params));
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  INSDIAG_ASSIGN_OR_RETURN(
      auto rows,
      db->Exec(
          absl::StrCat(
              "SELECT event_id, ", Micros("event_time"),
              ", coalesce(token_id::text, ''), display_name, role, "
              "method, resource, peer, code, message FROM audit_events "
              "WHERE ($2::text IS NULL OR resource = $2) AND ($3::uuid IS NULL OR token_id = $3) AND ",
              after, " ORDER BY event_id DESC LIMIT $1"),
          params));
  std::vector<AuditEvent> events;
  const int shown = std::min(rows.rows(), size);
  for (int r = 0; r < shown; ++r) {
    AuditEvent& e = events.emplace_back();
    e.name = absl::StrCat("auditEvents/", rows.String(r, 0));
    e.event_time = absl::FromUnixMicros(internal::IntOr0(rows, r, 1));
    if (!rows.Get(r, 2).empty()) e.token = absl::StrCat("tokens/", rows.String(r, 2));
    e.display_name = rows.String(r, 3);
    e.role = RoleFromName(rows.Get(r, 4));
    e.method = rows.String(r, 5);
    e.resource = rows.String(r, 6);
    e.peer = rows.String(r, 7);
    e.code = rows.String(r, 8);
    e.message = rows.String(r, 9);
  }
  std::string next;
  if (rows.rows() > size) next = internal::EncodeToken("", rows.String(shown - 1, 0));
  return std::make_pair(std::move(events), next);
}

}  // namespace insdiag::kb
