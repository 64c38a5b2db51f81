// The API's pieces that need no protobuf (proto/base/): the digest of bytes
// and a string as JSON.
#include <absl/strings/escaping.h>
#include <gtest/gtest.h>

#include <string>

#include "insdiag/api/json_string.h"
#include "insdiag/api/sha256.h"

namespace insdiag::api {
namespace {

TEST(Sha256Test, IsTheRawDigestOfFipsVectors) {
  // FIPS 180-2, appendix B.1, and the digest of no bytes.
  EXPECT_EQ(absl::BytesToHexString(Sha256("abc")),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(absl::BytesToHexString(Sha256("")),
            "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(Sha256("abc").size(), 32U);
}

TEST(JsonStringTest, EscapesQuoteBackslashAndControlCharactersOnly) {
  EXPECT_EQ(JsonString(""), R"("")");
  EXPECT_EQ(JsonString(R"(say "hi" \ bye)"), R"("say \"hi\" \\ bye")");
  EXPECT_EQ(JsonString(std::string("a\nb\tc\x1f", 6) + std::string(1, '\0')), R"("a\u000ab\u0009c\u001f\u0000")");
  EXPECT_EQ(JsonString("Grad °C ✓/"), "\"Grad °C ✓/\"");
}

}  // namespace
}  // namespace insdiag::api
