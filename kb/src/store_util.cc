#include "store_util.h"

#include <absl/strings/escaping.h>
#include <absl/strings/match.h>
#include <absl/strings/numbers.h>
#include <absl/strings/str_cat.h>
#include <absl/strings/str_join.h>
#include <absl/strings/str_split.h>
#include <absl/time/time.h>

#include <algorithm>
#include <cctype>

#include "insdiag/engine/status_macros.h"

namespace insdiag::kb::internal {

bool IsUuid(std::string_view text) {
  return text.size() == 36 && std::all_of(text.begin(), text.end(), [](char c) {
           return std::isxdigit(static_cast<unsigned char>(c)) || c == '-';
         }) && text[8] == '-' && text[13] == '-' && text[18] == '-' && text[23] == '-';
}

absl::StatusOr<std::string> UuidOf(const std::string& name, const api::Collection& collection,
                                   const std::string& field) {
  auto id = api::ResourceId(name, collection, field);
  if (!id.ok()) return id;
  if (!IsUuid(*id)) {
    return absl::InvalidArgumentError(absl::StrCat(field, ": '", name, "': the id after ",
                                                   std::string(collection.segment),
                                                   "/ is not a UUID"));
  }
  return id;
}

std::string Micros(const std::string& column) {
  return absl::StrCat("(extract(epoch FROM ", column, ") * 1000000)::bigint");
}

std::string TimeText(absl::Time t) {
  return absl::FormatTime("%Y-%m-%d %H:%M:%E6S+00", absl::FromUnixMicros(absl::ToUnixMicros(t)), absl::UTCTimeZone());
}

std::string EncodeToken(const std::string& a, const std::string& b) {
  return absl::WebSafeBase64Escape(absl::StrCat(a, "|", b));
}

absl::StatusOr<std::pair<std::string, std::string>> DecodeToken(const std::string& token) {
  std::string raw;
  if (absl::WebSafeBase64Unescape(token, &raw)) {
    const auto bar = raw.find('|');
    if (bar != std::string::npos) return std::make_pair(raw.substr(0, bar), raw.substr(bar + 1));
  }
  return absl::InvalidArgumentError("page_token is not one this server issued");
}

absl::StatusOr<std::string> KeysetCondition(const std::string& page_token, const std::string& time_column,
                                            const std::string& uuid_column, KeysetOrder order,
                                            std::vector<Param>& params) {
  return KeysetAfter(page_token, {{time_column, "timestamptz"}, {uuid_column, "uuid"}}, order, params);
}

namespace {

// Whether a token's value reads as the SQL type it is cast to; timestamps
// and text are left to the SQL (a timestamp the server wrote always parses).
bool ReadsAs(const std::string& value, const std::string& sql_type) {
  if (sql_type == "uuid") return IsUuid(value);
  if (sql_type == "bigint") {
    std::int64_t v = 0;
    return absl::SimpleAtoi(value, &v);
  }
  if (sql_type == "double precision") {
    double v = 0.0;
    return absl::SimpleAtod(value, &v);
  }
  return true;
}

}  // namespace

absl::StatusOr<std::string> KeysetAfter(const std::string& page_token, const std::vector<KeyColumn>& key,
                                        KeysetOrder order, std::vector<Param>& params) {
  if (page_token.empty()) return std::string("true");
  INSDIAG_ASSIGN_OR_RETURN(const auto values, DecodeToken(page_token));
  if (key.empty() || key.size() > 2) return absl::InternalError("a keyset of one or two columns");
  // A one-column key is the token's second value.
  const std::vector<std::string> parts = key.size() == 1 ? std::vector<std::string>{values.second}
                                                         : std::vector<std::string>{values.first, values.second};
  std::vector<std::string> columns, placeholders;
  for (std::size_t k = 0; k < key.size(); ++k) {
    if (!ReadsAs(parts[k], key[k].sql_type)) {
      return absl::InvalidArgumentError("page_token is not one this server issued");
    }
    params.push_back(Param::Text(parts[k]));
    columns.push_back(key[k].expression);
    placeholders.push_back(absl::StrCat("$", params.size(), "::", key[k].sql_type));
  }
  return absl::StrCat("(", absl::StrJoin(columns, ", "), ") ", order == KeysetOrder::kDescending ? "<" : ">",
                      " (", absl::StrJoin(placeholders, ", "), ")");
}

int ClampPageSize(int page_size) { return std::clamp(page_size <= 0 ? 50 : page_size, 1, 1000); }

std::string BoolText(bool b) { return b ? "true" : "false"; }

std::int64_t IntOr0(const Result& rows, int row, int column) {
  if (rows.IsNull(row, column)) return 0;
  auto v = rows.Int(row, column);
  return v.ok() ? *v : 0;
}

double DoubleOr0(const Result& rows, int row, int column) { return rows.OptionalDouble(row, column).value_or(0.0); }

std::string TextArrayLiteral(const std::vector<std::string>& values) {
  std::string out = "{";
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i > 0) out += ',';
    out += '"';
    for (char c : values[i]) {
      if (c == '"' || c == '\\') out += '\\';
      out += c;
    }
    out += '"';
  }
  return out + "}";
}

std::vector<std::string> ParseTextArray(std::string_view literal) {
  std::vector<std::string> out;
  if (literal.size() < 2) return out;
  std::string current;
  bool quoted = false, in_item = false;
  for (std::size_t i = 1; i + 1 < literal.size(); ++i) {
    const char c = literal[i];
    if (quoted) {
      if (c == '\\' && i + 2 < literal.size()) {
        current += literal[++i];
      } else if (c == '"') {
        quoted = false;
      } else {
        current += c;
      }
    } else if (c == '"') {
      quoted = true;
      in_item = true;
    } else if (c == ',') {
      out.push_back(current);
      current.clear();
      in_item = false;
    } else {
      current += c;
      in_item = true;
    }
  }
  if (in_item || !current.empty()) out.push_back(current);
  return out;
}

}  // namespace insdiag::kb::internal
