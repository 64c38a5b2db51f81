// libpq behind RAII: a connection, query results, parameterised statements and
// transactions. Nothing outside kb/ sees a PGconn or PGresult.
//
// Every statement is parameterised ($1, $2, …); values travel in text format
// except byte strings, which travel in binary (no escaping, no hex doubling).
#pragma once

#include <absl/functional/function_ref.h>
#include <absl/status/status.h>
#include <absl/status/statusor.h>
#include <libpq-fe.h>

#include <cstdint>
#include <initializer_list>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace insdiag::kb {

// A statement's error carries this payload (its SQLSTATE) and ends its
// message with " [the statement's first 80 characters]": for the server's
// log, which the status mapping writes it to; clients never see the SQL.
inline constexpr char kSqlErrorPayload[] = "type.googleapis.com/insdiag.kb.SqlError";

// One statement parameter: SQL NULL, a text value, or raw bytes (bytea).
class Param {
 public:
  static Param Null() { return Param(std::nullopt, false); }
  static Param Text(std::string value) { return Param(std::move(value), false); }
  static Param Bytes(std::string bytes) { return Param(std::move(bytes), true); }
  static Param Int(std::int64_t value) { return Text(std::to_string(value)); }
  // Shortest text that reads back to the same double.
  static Param Double(double value);
  // NULL when absent.
  static Param OptionalDouble(std::optional<double> value) {
    return value ? Double(*value) : Null();
  }
  // NULL for an empty string.
  static Param TextOrNull(std::string value) {
    return value.empty() ? Null() : Text(std::move(value));
  }
  // A text[] value as its array literal ('{"a","b"}'); the statement casts
  // it ($1::text[]).
  static Param TextArray(const std::vector<std::string>& values);

  const std::optional<std::string>& value() const { return value_; }
  bool binary() const { return binary_; }

 private:
  Param(std::optional<std::string> value, bool binary) : value_(std::move(value)), binary_(binary) {}
  std::optional<std::string> value_;
  bool binary_;
};

enum class ResultFormat { kText, kBinary };

// The rows of one statement's result.
class Result {
 public:
  int rows() const { return PQntuples(result_.get()); }
  int columns() const { return PQnfields(result_.get()); }
  bool IsNull(int row, int column) const { return PQgetisnull(result_.get(), row, column) != 0; }
  // The value as returned (text, or raw bytes for binary results).
  std::string_view Get(int row, int column) const;
  std::string String(int row, int column) const { return std::string(Get(row, column)); }
  absl::StatusOr<std::int64_t> Int(int row, int column) const;
  absl::StatusOr<double> Double(int row, int column) const;
  std::optional<double> OptionalDouble(int row, int column) const;
  bool Bool(int row, int column) const { return Get(row, column) == "t"; }
  // Rows affected by INSERT/UPDATE/DELETE.
  std::int64_t AffectedRows() const;

 private:
  friend class Connection;
  struct Deleter {
    void operator()(PGresult* result) const { PQclear(result); }
  };
  explicit Result(PGresult* result) : result_(result) {}
  std::unique_ptr<PGresult, Deleter> result_;
};

class Connection {
 public:
  // Connects with a libpq URL or key=value string. UNAVAILABLE when the server
  // cannot be reached.
  static absl::StatusOr<Connection> Open(const std::string& url);

  // Runs one parameterised statement. SQLSTATEs map onto canonical codes:
  // unique violation → ALREADY_EXISTS, other integrity violations →
  // FAILED_PRECONDITION, lost connection → UNAVAILABLE, others → INTERNAL.
  absl::StatusOr<Result> Exec(std::string_view sql, const std::vector<Param>& params = {},
                              ResultFormat format = ResultFormat::kText);
  absl::StatusOr<Result> Exec(std::string_view sql, std::initializer_list<Param> params,
                              ResultFormat format = ResultFormat::kText) {
    return Exec(sql, std::vector<Param>(params), format);
  }

  // Runs a script of several statements without parameters (migrations).
  absl::Status ExecScript(std::string_view sql);

  // `name` quoted as an SQL identifier by libpq (PQescapeIdentifier), for
  // statements that take no parameters in that place (CREATE DATABASE).
  absl::StatusOr<std::string> QuoteIdentifier(std::string_view name);

  // Creates database `name` on this connection's server unless it exists
  // (an embedded cluster's first start).
  absl::Status CreateDatabaseIfMissing(std::string_view name);

  // OK when the server answers a trivial query (health checking).
  absl::Status Ping();

  // COPY … FROM STDIN in text format: `produce` appends rows (tab-separated,
  // newline-terminated) to its buffer and returns false once it has no more.
  // Returns the number of rows COPY reports.
  absl::StatusOr<std::int64_t> CopyIn(std::string_view copy_sql, absl::FunctionRef<bool(std::string&)> produce);

  // Runs `body` inside BEGIN … COMMIT; rolls back when it fails.
  absl::Status InTransaction(absl::FunctionRef<absl::Status()> body);

  // False once the connection broke; a pool then drops it.
  bool healthy() const;

 private:
  struct Deleter {
    void operator()(PGconn* conn) const { PQfinish(conn); }
  };
  explicit Connection(PGconn* conn) : conn_(conn) {}
  absl::StatusOr<Result> Check(PGresult* raw, std::string_view sql);
  std::unique_ptr<PGconn, Deleter> conn_;
  // The connection failed under a statement (no SQLSTATE: libpq's own
  // error), whatever libpq's status says yet: a pool does not reuse it.
  bool lost_ = false;
};

// A stable 64-bit key for pg_advisory_lock derived from a name.
std::int64_t AdvisoryLockKey(std::string_view name);

}  // namespace insdiag::kb
