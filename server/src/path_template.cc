#include "insdiag/server/path_template.h"

#include <absl/strings/str_cat.h>
#include <absl/strings/str_join.h>
#include <absl/strings/str_split.h>

namespace insdiag::server {
namespace {

absl::Status Malformed(const std::string& text, const std::string& why) {
  return absl::InvalidArgumentError(absl::StrCat("path template '", text, "': ", why));
}

}  // namespace

absl::StatusOr<PathTemplate> PathTemplate::Parse(const std::string& text) {
  PathTemplate parsed;
  parsed.text_ = text;
  if (text.empty() || text[0] != '/') return Malformed(text, "must start with '/'");
  std::string body = text.substr(1);
  // The verb is a ':' after the last '/' and outside braces.
  const auto last_slash = body.rfind('/');
  const auto last_close = body.rfind('}');
  const auto verb_colon = body.rfind(':');
  if (verb_colon != std::string::npos && (last_slash == std::string::npos || verb_colon > last_slash) &&
      (last_close == std::string::npos || verb_colon > last_close)) {
    parsed.verb_ = body.substr(verb_colon + 1);
    body.resize(verb_colon);
  }

  std::optional<Variable> open;
  // Appends one segment; `closes` ends the open variable after it.
  const auto add = [&](const std::string& piece, bool closes) {
    parsed.segments_.push_back(
        {piece == "**" ? Kind::kRest : piece == "*" ? Kind::kWildcard : Kind::kLiteral, piece});
    if (closes) {
      open->end = parsed.segments_.size();
      parsed.variables_.push_back(*open);
      open.reset();
    }
  };
  for (absl::string_view split_piece : absl::StrSplit(body, '/')) {
    std::string piece(split_piece);
    const bool closes = !piece.empty() && piece.back() == '}';
    if (closes) piece.pop_back();
    if (!piece.empty() && piece.front() == '{') {
      if (open) return Malformed(text, "nested variables");
      piece.erase(0, 1);
      const auto equals = piece.find('=');
      open = Variable{equals == std::string::npos ? piece : piece.substr(0, equals), parsed.segments_.size(), 0};
      if (open->field.empty()) return Malformed(text, "a variable without a field name");
      if (!closes && equals == std::string::npos) return Malformed(text, "unclosed variable");
      add(equals == std::string::npos ? "*" : piece.substr(equals + 1), closes);
      continue;
    }
    if (closes && !open) return Malformed(text, "'}' without '{'");
    if (piece.empty()) return Malformed(text, "an empty segment");
    if (piece.find_first_of("{}=") != std::string::npos) return Malformed(text, "stray '{', '}' or '='");
    add(piece, closes);
  }
  if (open) return Malformed(text, "unclosed variable");
  for (std::size_t i = 0; i + 1 < parsed.segments_.size(); ++i) {
    if (parsed.segments_[i].kind == Kind::kRest) return Malformed(text, "'**' must be the last segment");
  }
  return parsed;
}

std::optional<std::map<std::string, std::string>> PathTemplate::Match(const std::string& path) const {
  if (path.empty() || path[0] != '/') return std::nullopt;
  std::string body = path.substr(1);
  if (has_verb()) {
    const std::string suffix = ":" + verb_;
    if (body.size() <= suffix.size() || body.compare(body.size() - suffix.size(), suffix.size(), suffix) != 0) {
      return std::nullopt;
    }
    body.resize(body.size() - suffix.size());
  }
  const std::vector<std::string> parts = absl::StrSplit(body, '/');
  std::vector<std::string> matched;  // per template segment, what it matched
  std::size_t at = 0;
  for (const auto& segment : segments_) {
    if (segment.kind == Kind::kRest) {
      if (at >= parts.size()) return std::nullopt;
      std::vector<std::string> rest(parts.begin() + static_cast<std::ptrdiff_t>(at), parts.end());
      matched.push_back(absl::StrJoin(rest, "/"));
      at = parts.size();
      continue;
    }
    if (at >= parts.size() || parts[at].empty()) return std::nullopt;
    // Without a verb in the template, a ':' in the last segment belongs to
    // some other route's verb (runs/x:download is not a run named x:download).
    if (segment.kind == Kind::kWildcard && !has_verb() && parts[at].find(':') != std::string::npos) {
      return std::nullopt;
    }
    if (segment.kind == Kind::kLiteral && parts[at] != segment.literal) return std::nullopt;
    matched.push_back(parts[at++]);
  }
  if (at != parts.size()) return std::nullopt;
  std::map<std::string, std::string> bindings;
  for (const auto& variable : variables_) {
    std::vector<std::string> pieces(matched.begin() + static_cast<std::ptrdiff_t>(variable.first),
                                    matched.begin() + static_cast<std::ptrdiff_t>(variable.end));
    bindings[variable.field] = absl::StrJoin(pieces, "/");
  }
  return bindings;
}

}  // namespace insdiag::server
