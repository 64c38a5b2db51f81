#include "request_edge.h"

#include <absl/strings/match.h>
#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>

#include "insdiag/benchrun/text_rules.h"

// Last: httplib.h pulls in <resolv.h>, whose `_res` macro breaks Eigen's headers.
#include <httplib.h>

namespace insdiag::server {
namespace {

// The headers the gateway puts into the in-process call's metadata.
constexpr std::string_view kForwardedHeaders[] = {"Authorization"};

// Why `text` may not become a request field, or empty: ill-formed UTF-8 or a
// control character (NUL cannot be stored in PostgreSQL text; a line break
// would forge log lines).
std::string CheckFieldText(std::string_view text) {
  if (const auto bad = benchrun::FindInvalidUtf8(text)) {
    return absl::StrFormat("byte 0x%02X at byte %d is not UTF-8", static_cast<unsigned char>(text[*bad]), *bad + 1);
  }
  for (std::size_t i = 0; i < text.size(); ++i) {
    const auto byte = static_cast<unsigned char>(text[i]);
    if (byte < 0x20 || byte == 0x7F) {
      return absl::StrFormat("control character 0x%02X at byte %d is not allowed", byte, i + 1);
    }
  }
  return {};
}

}  // namespace

absl::Status CheckForwardedHeader(std::string_view name, std::string_view value) {
  for (std::size_t i = 0; i < value.size(); ++i) {
    const auto byte = static_cast<unsigned char>(value[i]);
    if (byte < 0x20 || byte > 0x7E) {
      return absl::UnauthenticatedError(absl::StrFormat(
          "header %s: byte 0x%02X at position %d is not allowed; the header holds printable ASCII only "
          "(0x20-0x7E), as 'Bearer <token>' does",
          name, byte, i + 1));
    }
  }
  return absl::OkStatus();
}

std::string UnreadableRequestMessage(int http_status) {
  switch (http_status) {
    case 413:
      return absl::StrCat("the request body is longer than ", kMaxRequestBodyBytes,
                          " bytes; upload larger runs over gRPC (docs/API.md, Limits)");
    case 414:
      return absl::StrCat("the request's URI is longer than ", kMaxHttpLineBytes, " bytes");
    case 400:
      return absl::StrCat("the request could not be read: a malformed request line or header, or a header line ",
                          "longer than ", kMaxHttpLineBytes, " bytes (docs/API.md, Limits)");
    default:
      return absl::StrCat("the request was refused with HTTP ", http_status);
  }
}

absl::Status CheckRequestEdge(const httplib::Request& request) {
  if (request.headers.size() > kMaxRequestHeaderCount) {
    return absl::InvalidArgumentError(absl::StrCat("the request has ", request.headers.size(),
                                                   " headers; at most ", kMaxRequestHeaderCount, " are read"));
  }
  std::size_t header_bytes = 0;
  for (const auto& [name, value] : request.headers) header_bytes += name.size() + value.size() + 4;  // ": ", CRLF
  if (header_bytes > kMaxRequestHeaderBytes) {
    return absl::InvalidArgumentError(absl::StrCat("the request's headers hold ", header_bytes, " bytes; at most ",
                                                   kMaxRequestHeaderBytes, " are read"));
  }
  for (const std::string_view forwarded : kForwardedHeaders) {
    const auto range = request.headers.equal_range(std::string(forwarded));
    for (auto it = range.first; it != range.second; ++it) {
      if (absl::Status status = CheckForwardedHeader(forwarded, it->second); !status.ok()) return status;
    }
  }
  if (std::string detail = CheckFieldText(request.path); !detail.empty()) {
    return absl::InvalidArgumentError(
        absl::StrCat("path '", benchrun::Utf8Printable(request.path), "': ", detail));
  }
  for (const auto& [name, value] : request.params) {
    if (std::string detail = CheckFieldText(name); !detail.empty()) {
      return absl::InvalidArgumentError(
          absl::StrCat("query parameter name '", benchrun::Utf8Printable(name), "': ", detail));
    }
    if (std::string detail = CheckFieldText(value); !detail.empty()) {
      return absl::InvalidArgumentError(
          absl::StrCat("query parameter '", benchrun::Utf8Printable(name), "': ", detail));
    }
  }
  return absl::OkStatus();
}

}  // namespace insdiag::server
