// The REST gateway's edge: what of an HTTP request may pass on to the
// services, checked before any call is made (docs/API.md, "Limits").
//
//   headers      at most kMaxRequestHeaderCount, kMaxRequestHeaderBytes in all
//   forwarded    a header that becomes gRPC metadata (Authorization) holds
//                printable ASCII only, 0x20–0x7E: gRPC refuses other bytes in
//                metadata, and the token's secret is ASCII anyway
//   path, query  UTF-8 without control characters: they become request
//                fields, resource names, SQL parameters and log text
#pragma once

#include <absl/status/status.h>

#include <cstddef>
#include <string>
#include <string_view>

namespace httplib {
struct Request;
}  // namespace httplib

namespace insdiag::server {

// Far above what any client sends (a browser's request is ~1 KiB of headers),
// small enough that a header flood costs nothing.
inline constexpr std::size_t kMaxRequestHeaderCount = 64;
inline constexpr std::size_t kMaxRequestHeaderBytes = 32 * 1024;
// The largest body the HTTP face reads: a 1-hour 50 Hz run is ~20 MB of CSV,
// the largest upload (RunService's sample limit) well under this.
inline constexpr std::size_t kMaxRequestBodyBytes = 1024 * 1024 * 1024;

// UNAUTHENTICATED naming the byte and its position when `value` of the
// header `name` holds a byte outside printable ASCII.
absl::Status CheckForwardedHeader(std::string_view name, std::string_view value);

// cpp-httplib's own limits, which it answers before the gateway sees the
// request (compiled into Debian's library): a request line or a header
// line of 8 KiB at most.
inline constexpr std::size_t kMaxHttpLineBytes = 8192;

// What a client is told when cpp-httplib itself refuses its request with
// `http_status` (400 unreadable, 413 too large, 414 URI too long) and no
// body: the rule it broke.
std::string UnreadableRequestMessage(int http_status);

// INVALID_ARGUMENT naming the part of the request (header count or size,
// path, query parameter) that breaks a rule above; UNAUTHENTICATED for a
// forwarded header.
absl::Status CheckRequestEdge(const httplib::Request& request);

}  // namespace insdiag::server
