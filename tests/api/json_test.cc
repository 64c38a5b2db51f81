// api::FromJson takes a value only in the JSON type its field has: what
// protobuf's own parser would stretch ("yes" for true, a string for a list)
// is refused naming the field.
#include "insdiag/api/json.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "insdiag/v1/access.pb.h"
#include "insdiag/v1/analyses.pb.h"
#include "insdiag/v1/runs.pb.h"

namespace insdiag::api {
namespace {

using ::testing::HasSubstr;

TEST(FromJson, BooleansAreTrueOrFalseOnly) {
  v1::Analysis analysis;
  for (const char* body : {R"({"discover":"yes"})", R"({"discover":"true"})"}) {
    const absl::Status status = FromJson(body, &analysis);
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << body;
    EXPECT_THAT(std::string(status.message()), HasSubstr("discover: expected true or false")) << body;
  }
  // A number protobuf's parser refuses itself, naming the field.
  EXPECT_THAT(std::string(FromJson(R"({"discover":1})", &analysis).message()), HasSubstr("discover"));
  ASSERT_TRUE(FromJson(R"({"discover":true,"run":"runs/x"})", &analysis).ok());
  EXPECT_TRUE(analysis.discover());
}

TEST(FromJson, AListTakesAnArrayAndAMessageAnObjectNamedByPath) {
  v1::Analysis analysis;
  EXPECT_THAT(std::string(FromJson(R"({"model":{"effects":"gyro"}})", &analysis).message()),
              HasSubstr("model.effects: expected an array, got a string"));
  EXPECT_THAT(std::string(FromJson(R"({"model":{"effects":["gyro_scale", 3]}})", &analysis).message()),
              HasSubstr("model.effects[1]"));
  // Refused by protobuf's parser or by the shape check, whichever sees it first.
  EXPECT_EQ(FromJson(R"({"model":"gyro"})", &analysis).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(FromJson(R"({"run":42})", &analysis).code(), absl::StatusCode::kInvalidArgument);
  ASSERT_TRUE(FromJson(R"({"model":{"effects":["gyro_scale"]},"baseline":null})", &analysis).ok());
  EXPECT_EQ(analysis.model().effects_size(), 1);
}

TEST(FromJson, NumbersMayBeStringsAsProto3WritesThemAndWellKnownTypesKeepTheirForms) {
  v1::ListRunsRequest list;
  ASSERT_TRUE(FromJson(R"({"pageSize":"20"})", &list).ok());
  EXPECT_EQ(list.page_size(), 20);
  EXPECT_THAT(std::string(FromJson(R"({"pageSize":true})", &list).message()), HasSubstr("page_size"));
  v1::CreateTokenRequest token;
  ASSERT_TRUE(FromJson(R"({"token":{"displayName":"a","role":"VIEWER","expireTime":"2030-01-01T00:00:00Z"}})", &token)
                  .ok());
  EXPECT_EQ(FromJson(R"({"token":{"expireTime":{"seconds":1}}})", &token).code(), absl::StatusCode::kInvalidArgument);
}

TEST(FromJson, AStringHoldsNoNulCharacter) {
  v1::CreateTokenRequest token;
  EXPECT_THAT(std::string(FromJson(R"({"token":{"displayName":"a\u0000b"}})", &token).message()),
              HasSubstr("token.displayName: the string holds U+0000"));
}

}  // namespace
}  // namespace insdiag::api
