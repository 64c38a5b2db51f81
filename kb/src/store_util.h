// Helpers the stores share: resource names, ids, timestamps, page tokens.
#pragma once

#include <absl/status/statusor.h>
#include <absl/time/time.h>

#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "insdiag/api/resource_names.h"
#include "insdiag/kb/pg.h"

namespace insdiag::kb::internal {

// As api::ResourceId, and the id must be a UUID.
absl::StatusOr<std::string> UuidOf(const std::string& name, const api::Collection& collection,
                                   const std::string& field);
bool IsUuid(std::string_view text);

// SQL expression of a timestamptz column as microseconds since the epoch.
std::string Micros(const std::string& column);
// A time as text PostgreSQL reads ("2024-01-31 12:00:00.000000+00"), to
// the microsecond (rounded down).
std::string TimeText(absl::Time t);

// Keyset page tokens: opaque base64 of "a|b".
std::string EncodeToken(const std::string& a, const std::string& b);
absl::StatusOr<std::pair<std::string, std::string>> DecodeToken(const std::string& token);

// Keyset pagination of rows ordered by (a timestamptz column, a UUID column),
// the token holding the last row's pair: "true" for the first page, else the
// SQL condition for the rows after it, its two values appended to `params`
// as the next two parameters. INVALID_ARGUMENT for a token this server did
// not issue (a key that is not a UUID never reaches the SQL).
// The key's order: down it ("<" the last row's key) or up it (">"); newest
// and oldest first for a time-ordered key.
enum class KeysetOrder { kDescending, kAscending, kNewestFirst = kDescending, kOldestFirst = kAscending };
absl::StatusOr<std::string> KeysetCondition(const std::string& page_token, const std::string& time_column,
                                            const std::string& uuid_column, KeysetOrder order,
                                            std::vector<Param>& params);

// The same for any sort key: one or two columns (an SQL expression each)
// with the SQL type their token values are cast to ("bigint", "double
// precision", "text", "uuid", "timestamptz"). A one-column key is the token's
// second value. A value that does not read as its type is refused as a
// token this server did not issue.
struct KeyColumn {
  std::string expression;
  std::string sql_type;
};
absl::StatusOr<std::string> KeysetAfter(const std::string& page_token, const std::vector<KeyColumn>& key,
                                        KeysetOrder order, std::vector<Param>& params);

int ClampPageSize(int page_size);  // default 50, within [1, 1000]

// A bool as the text of a query parameter ("true", "false").
std::string BoolText(bool b);

// Int column or 0.
std::int64_t IntOr0(const Result& rows, int row, int column);
double DoubleOr0(const Result& rows, int row, int column);

// A pg text[] literal of `values` ('{"a","b"}') and back.
std::string TextArrayLiteral(const std::vector<std::string>& values);
std::vector<std::string> ParseTextArray(std::string_view literal);

}  // namespace insdiag::kb::internal
