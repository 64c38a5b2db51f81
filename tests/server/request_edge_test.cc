// The REST gateway's edge (request_edge.h): what it lets on to gRPC metadata,
// request fields and logs, and how it names what it refuses.
#include "request_edge.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

// Last: httplib.h pulls in <resolv.h>, whose `_res` macro breaks Eigen.
#include <httplib.h>

namespace insdiag::server {
namespace {

using ::testing::HasSubstr;

httplib::Request GetWithToken(const std::string& authorization) {
  httplib::Request request;
  request.method = "GET";
  request.path = "/v1/runs";
  request.headers.emplace("Authorization", authorization);
  return request;
}

// The bytes that once aborted insdiagd inside gRPC.
TEST(RequestEdge, AnAuthorizationOutsidePrintableAsciiIsUnauthenticatedNamingTheByte) {
  const absl::Status high = CheckRequestEdge(GetWithToken("Bearer \xff"));
  EXPECT_EQ(high.code(), absl::StatusCode::kUnauthenticated);
  EXPECT_THAT(std::string(high.message()), HasSubstr("header Authorization: byte 0xFF at position 8 is not allowed"));
  EXPECT_THAT(std::string(CheckRequestEdge(GetWithToken("Bearer \x01\x02" "abc")).message()), HasSubstr("byte 0x01 at position 8"));
  EXPECT_THAT(std::string(CheckRequestEdge(GetWithToken("Bearer caf\xc3\xa9")).message()), HasSubstr("byte 0xC3 at position 11"));
  EXPECT_THAT(std::string(CheckRequestEdge(GetWithToken(std::string("Bearer a\0b", 10))).message()), HasSubstr("0x00"));
  EXPECT_TRUE(CheckRequestEdge(GetWithToken("Bearer idt_0123456789abcdef")).ok());
}

TEST(RequestEdge, PathsAndQueryParametersAreUtf8WithoutControlCharacters) {
  httplib::Request request = GetWithToken("Bearer t");
  request.params.emplace("requestId", std::string("r\0", 2));
  EXPECT_THAT(std::string(CheckRequestEdge(request).message()),
              HasSubstr("query parameter 'requestId': control character 0x00 at byte 2"));
  request.params.clear();
  request.params.emplace("unit_serial", "INS\xff");
  EXPECT_THAT(std::string(CheckRequestEdge(request).message()), HasSubstr("query parameter 'unit_serial': byte 0xFF at byte 4 is not UTF-8"));
  request.params.clear();
  request.path = "/v1/units/INS\xc0\xaf";
  const absl::Status path = CheckRequestEdge(request);
  EXPECT_EQ(path.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(path.message()), HasSubstr("path '/v1/units/INS\\xC0\\xAF': byte 0xC0"));
  request.path = "/v1/units/INS-caf\xc3\xa9";
  EXPECT_TRUE(CheckRequestEdge(request).ok());
}

TEST(RequestEdge, HeadersAreBoundedInCountAndSize) {
  httplib::Request many = GetWithToken("Bearer t");
  for (std::size_t i = 0; i < kMaxRequestHeaderCount; ++i) many.headers.emplace("X-Filler-" + std::to_string(i), "x");
  EXPECT_THAT(std::string(CheckRequestEdge(many).message()), HasSubstr("at most 64 are read"));
  httplib::Request large = GetWithToken("Bearer t");
  for (int i = 0; i < 8; ++i) large.headers.emplace("X-Big-" + std::to_string(i), std::string(5000, 'b'));
  EXPECT_THAT(std::string(CheckRequestEdge(large).message()), HasSubstr("at most 32768 are read"));
}

}  // namespace
}  // namespace insdiag::server
