#include "insdiag/kb/pg.h"

#include <absl/strings/cord.h>
#include <absl/strings/numbers.h>
#include <absl/strings/str_cat.h>

#include <charconv>
#include <cstdlib>

#include "insdiag/engine/status_macros.h"
#include "store_util.h"

namespace insdiag::kb {
namespace {

absl::Status StatusFromSqlState(std::string_view sqlstate, std::string message) {
  // Class 23 is integrity constraint violations; 08 connection exceptions;
  // 57P01..03 the server shutting down. The rest are our bugs or the
  // server's trouble.
  if (sqlstate == "23505") return absl::AlreadyExistsError(std::move(message));
  if (sqlstate.starts_with("23")) return absl::FailedPreconditionError(std::move(message));
  if (sqlstate.starts_with("08") || sqlstate.starts_with("57P")) {
    return absl::UnavailableError(std::move(message));
  }
  if (sqlstate == "40001" || sqlstate == "40P01") return absl::AbortedError(std::move(message));
  return absl::InternalError(std::move(message));
}

// Debian's abseil keeps its own string_view type, distinct from std's.
absl::string_view Absl(std::string_view text) { return {text.data(), text.size()}; }

std::string FirstLine(std::string_view text) {
  const auto end = text.find('\n');
  return std::string(end == std::string_view::npos ? text : text.substr(0, end));
}

}  // namespace

Param Param::Double(double value) {
  char buffer[32];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  return Text(std::string(buffer, end));
}

Param Param::TextArray(const std::vector<std::string>& values) { return Text(internal::TextArrayLiteral(values)); }

std::string_view Result::Get(int row, int column) const {
  return {PQgetvalue(result_.get(), row, column),
          static_cast<std::size_t>(PQgetlength(result_.get(), row, column))};
}

absl::StatusOr<std::int64_t> Result::Int(int row, int column) const {
  std::int64_t value = 0;
  if (!absl::SimpleAtoi(Absl(Get(row, column)), &value)) {
    return absl::InternalError(absl::StrCat("column ", PQfname(result_.get(), column), " is not an integer"));
  }
  return value;
}

absl::StatusOr<double> Result::Double(int row, int column) const {
  double value = 0;
  if (!absl::SimpleAtod(Absl(Get(row, column)), &value)) {
    return absl::InternalError(absl::StrCat("column ", PQfname(result_.get(), column), " is not a number"));
  }
  return value;
}

std::optional<double> Result::OptionalDouble(int row, int column) const {
  if (IsNull(row, column)) return std::nullopt;
  double value = 0;
  if (!absl::SimpleAtod(Absl(Get(row, column)), &value)) return std::nullopt;
  return value;
}

std::int64_t Result::AffectedRows() const {
  std::int64_t value = 0;
  return absl::SimpleAtoi(PQcmdTuples(result_.get()), &value) ? value : 0;
}

absl::StatusOr<Connection> Connection::Open(const std::string& url) {
  Connection connection(PQconnectdb(url.c_str()));
  if (!connection.conn_) return absl::ResourceExhaustedError("libpq could not allocate a connection");
  if (PQstatus(connection.conn_.get()) != CONNECTION_OK) {
    return absl::UnavailableError(
        absl::StrCat("cannot connect to PostgreSQL: ", FirstLine(PQerrorMessage(connection.conn_.get()))));
  }
  // Quiet NOTICEs (e.g. "relation already exists, skipping") that libpq
  // would otherwise print on stderr.
  PQsetNoticeProcessor(connection.conn_.get(), [](void*, const char*) {}, nullptr);
  return connection;
}

absl::StatusOr<Result> Connection::Check(PGresult* raw, std::string_view sql) {
  Result result(raw);
  const auto status = raw ? PQresultStatus(raw) : PGRES_FATAL_ERROR;
  if (status == PGRES_COMMAND_OK || status == PGRES_TUPLES_OK) return result;
  if (!raw) {
    lost_ = true;
    return absl::UnavailableError(FirstLine(PQerrorMessage(conn_.get())));
  }
  const char* sqlstate = PQresultErrorField(raw, PG_DIAG_SQLSTATE);
  // Every error of the server carries a SQLSTATE; one without is libpq's
  // own, about the connection: "server closed the connection unexpectedly"
  // while PostgreSQL restarts, before libpq marks the connection bad.
  if (sqlstate == nullptr || *sqlstate == '\0') {
    lost_ = true;
    return absl::UnavailableError(absl::StrCat(
        "PostgreSQL closed the connection during the request (it stopped or restarted: a full disk "
        "or a crash, see its log): ",
        FirstLine(PQresultErrorMessage(raw))));
  }
  absl::Status refused = StatusFromSqlState(
      sqlstate, absl::StrCat(FirstLine(PQresultErrorMessage(raw)), " [", FirstLine(sql.substr(0, 80)), "]"));
  refused.SetPayload(kSqlErrorPayload, absl::Cord(sqlstate));
  return refused;
}

absl::StatusOr<Result> Connection::Exec(std::string_view sql, const std::vector<Param>& params,
                                        ResultFormat format) {
  std::vector<const char*> values;
  std::vector<int> lengths;
  std::vector<int> formats;
  values.reserve(params.size());
  for (const auto& param : params) {
    values.push_back(param.value() ? param.value()->data() : nullptr);
    lengths.push_back(param.value() ? static_cast<int>(param.value()->size()) : 0);
    formats.push_back(param.binary() ? 1 : 0);
  }
  const std::string statement(sql);
  return Check(PQexecParams(conn_.get(), statement.c_str(), static_cast<int>(params.size()), nullptr,
                            values.data(), lengths.data(), formats.data(),
                            format == ResultFormat::kBinary ? 1 : 0),
               sql);
}

absl::Status Connection::ExecScript(std::string_view sql) {
  const std::string script(sql);
  return Check(PQexec(conn_.get(), script.c_str()), sql).status();
}

absl::StatusOr<std::string> Connection::QuoteIdentifier(std::string_view name) {
  char* quoted = PQescapeIdentifier(conn_.get(), name.data(), name.size());
  if (quoted == nullptr) {
    return absl::InvalidArgumentError(absl::StrCat(
        "'", std::string(name),
        "' cannot be quoted as an identifier: ", FirstLine(PQerrorMessage(conn_.get()))));
  }
  std::string result(quoted);
  PQfreemem(quoted);
  return result;
}

absl::Status Connection::CreateDatabaseIfMissing(std::string_view name) {
  INSDIAG_ASSIGN_OR_RETURN(auto exists, Exec("SELECT 1 FROM pg_database WHERE datname = $1",
                                             {Param::Text(std::string(name))}));
  if (exists.rows() > 0) return absl::OkStatus();
  // CREATE DATABASE takes no parameters: the name goes in as a quoted identifier.
  INSDIAG_ASSIGN_OR_RETURN(auto quoted, QuoteIdentifier(name));
  return ExecScript(absl::StrCat("CREATE DATABASE ", quoted));
}

absl::Status Connection::Ping() { return Exec("SELECT 1").status(); }

absl::StatusOr<std::int64_t> Connection::CopyIn(std::string_view copy_sql,
                                                absl::FunctionRef<bool(std::string&)> produce) {
  const std::string statement(copy_sql);
  {
    Result started(PQexec(conn_.get(), statement.c_str()));
    if (PQresultStatus(started.result_.get()) != PGRES_COPY_IN) return Check(started.result_.release(), copy_sql).status();
  }
  std::string buffer;
  bool more = true;
  while (more) {
    buffer.clear();
    more = produce(buffer);
    if (!buffer.empty() &&
        PQputCopyData(conn_.get(), buffer.data(), static_cast<int>(buffer.size())) != 1) {
      return absl::UnavailableError(absl::StrCat("COPY: ", FirstLine(PQerrorMessage(conn_.get()))));
    }
  }
  if (PQputCopyEnd(conn_.get(), nullptr) != 1) {
    return absl::UnavailableError(absl::StrCat("COPY: ", FirstLine(PQerrorMessage(conn_.get()))));
  }
  auto done = Check(PQgetResult(conn_.get()), copy_sql);
  // Drain: libpq wants PQgetResult called until it returns null.
  while (PGresult* extra = PQgetResult(conn_.get())) PQclear(extra);
  if (!done.ok()) return done.status();
  return done->AffectedRows();
}

absl::Status Connection::InTransaction(absl::FunctionRef<absl::Status()> body) {
  if (auto begun = Exec("BEGIN"); !begun.ok()) return begun.status();
  absl::Status status = body();
  if (status.ok()) {
    status = Exec("COMMIT").status();
    if (status.ok()) return status;
  }
  // A failed ROLLBACK means the connection is gone, and with it the
  // transaction: the original error is what the caller needs.
  (void)Exec("ROLLBACK");
  return status;
}

bool Connection::healthy() const { return !lost_ && PQstatus(conn_.get()) == CONNECTION_OK; }

std::int64_t AdvisoryLockKey(std::string_view name) {
  // FNV-1a: stable across builds and platforms, unlike std::hash.
  std::uint64_t hash = 14695981039346656037ULL;
  for (const unsigned char c : name) {
    hash ^= c;
    hash *= 1099511628211ULL;
  }
  return static_cast<std::int64_t>(hash);
}

}  // namespace insdiag::kb
