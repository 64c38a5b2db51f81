// URL path templates of google.api.http rules, e.g.
//   /v1/runs                       literal segments
//   /v1/{name=runs/*}              a variable bound to "runs/<one segment>"
//   /v1/{parent=units/*}/modules   a variable inside the path
//   /v1/{name=analyses/*}:watch    a custom verb after the last segment
//   /v1/{path=**}                  ** matches the rest of the path
// `{field}` alone means `{field=*}`. A variable's value is its matched
// segments joined with '/'.
#pragma once

#include <absl/status/statusor.h>

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace insdiag::server {

class PathTemplate {
 public:
  // INVALID_ARGUMENT for a template outside the grammar above.
  static absl::StatusOr<PathTemplate> Parse(const std::string& text);

  // Variable bindings (field path → value) when `path` matches.
  std::optional<std::map<std::string, std::string>> Match(const std::string& path) const;

  bool has_verb() const { return !verb_.empty(); }
  const std::string& text() const { return text_; }

 private:
  enum class Kind { kLiteral, kWildcard, kRest };
  struct Segment {
    Kind kind;
    std::string literal;
  };
  struct Variable {
    std::string field;
    std::size_t first = 0;  // segment indices [first, end)
    std::size_t end = 0;
  };
  std::string text_;
  std::vector<Segment> segments_;
  std::vector<Variable> variables_;
  std::string verb_;
};

}  // namespace insdiag::server
