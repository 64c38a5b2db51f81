#include "insdiag/server/status_mapping.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "google/rpc/error_details.pb.h"
#include "google/rpc/status.pb.h"
#include "insdiag/benchrun/bench_run_validation.h"
#include "insdiag/kb/pg.h"

namespace insdiag::server {
namespace {

using ::testing::HasSubstr;

TEST(StatusMapping, CanonicalCodesMapOneToOneOntoGrpc) {
  for (int code = 1; code <= 16; ++code) {
    const absl::Status status(static_cast<absl::StatusCode>(code), "why");
    const grpc::Status mapped = ToGrpcStatus(status);
    EXPECT_EQ(static_cast<int>(mapped.error_code()), code);
    const bool servers_trouble = status.code() == absl::StatusCode::kInternal ||
                                 status.code() == absl::StatusCode::kUnknown ||
                                 status.code() == absl::StatusCode::kDataLoss;
    if (!servers_trouble) {
      EXPECT_EQ(mapped.error_message(), "why");
    }
    EXPECT_EQ(FromGrpcStatus(mapped).code(), status.code());
  }
  EXPECT_TRUE(ToGrpcStatus(absl::OkStatus()).ok());
}

// The server's own trouble reaches the client as a reference into the log,
// never as its detail (SQL, paths); a refusal the database gives keeps its
// words without the statement.
TEST(StatusMapping, InternalErrorsCarryAReferenceAndNeverTheirDetail) {
  const absl::Status sql_failure = absl::InternalError(
      "ERROR: time zone displacement out of range [WITH made AS (INSERT INTO access_tokens (display_name]");
  const grpc::Status mapped = ToGrpcStatus(sql_failure);
  EXPECT_EQ(mapped.error_code(), grpc::StatusCode::INTERNAL);
  EXPECT_THAT(mapped.error_message(), ::testing::MatchesRegex("internal error [0-9a-f]{8}; the server's log .*"));
  EXPECT_THAT(mapped.error_message(), ::testing::Not(HasSubstr("INSERT")));
  EXPECT_THAT(ToHttpError(mapped).json_body, ::testing::Not(HasSubstr("access_tokens")));
  EXPECT_NE(ToGrpcStatus(sql_failure).error_message(), mapped.error_message()) << "one reference per error";

  absl::Status constraint = absl::FailedPreconditionError("violates foreign key constraint [DELETE FROM runs WHERE]");
  constraint.SetPayload(kb::kSqlErrorPayload, absl::Cord("23503"));
  EXPECT_EQ(ToGrpcStatus(constraint).error_message(), "violates foreign key constraint");
}

TEST(StatusMapping, BenchRunRefusalBecomesBadRequestAndErrorInfo) {
  const absl::Status refusal =
      benchrun::Refusal({.source = "run.csv", .line = 12, .column = 23, .field = "gyro_z"}, "'abc' is not a number");
  const grpc::Status mapped = ToGrpcStatus(refusal);
  EXPECT_EQ(mapped.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  google::rpc::Status details;
  ASSERT_TRUE(details.ParseFromString(mapped.error_details()));
  EXPECT_EQ(details.code(), 3);
  google::rpc::BadRequest bad_request;
  google::rpc::ErrorInfo info;
  for (const auto& any : details.details()) {
    if (any.Is<google::rpc::BadRequest>()) any.UnpackTo(&bad_request);
    if (any.Is<google::rpc::ErrorInfo>()) any.UnpackTo(&info);
  }
  ASSERT_EQ(bad_request.field_violations_size(), 1);
  EXPECT_EQ(bad_request.field_violations(0).field(), "run.csv:12:23 gyro_z");
  EXPECT_EQ(info.reason(), "INVALID_BENCH_RUN");
  EXPECT_EQ(info.metadata().at("line"), "12");
  EXPECT_EQ(info.metadata().at("column"), "23");

  const HttpError http = ToHttpError(mapped);
  EXPECT_EQ(http.http_status, 400);
  EXPECT_THAT(http.json_body, HasSubstr(R"("status":"INVALID_ARGUMENT")"));
  EXPECT_THAT(http.json_body, HasSubstr(R"("code":400)"));
  EXPECT_THAT(http.json_body, HasSubstr("run.csv:12:23"));
  EXPECT_THAT(http.json_body, HasSubstr("type.googleapis.com/google.rpc.BadRequest"));
}

TEST(StatusMapping, ErrorInfoPayloadTravelsToBothFaces) {
  const absl::Status status =
      WithErrorInfo(absl::InvalidArgumentError("sha256 mismatch"), "SHA256_MISMATCH", {{"expected", "ab"}});
  const HttpError http = ToHttpError(ToGrpcStatus(status));
  EXPECT_THAT(http.json_body, HasSubstr(R"("reason":"SHA256_MISMATCH")"));
  EXPECT_THAT(http.json_body, HasSubstr(R"("domain":"insdiag.v1")"));
}

TEST(StatusMapping, HttpStatusesFollowGoogleRpcCode) {
  EXPECT_EQ(HttpStatusOf(grpc::StatusCode::NOT_FOUND), 404);
  EXPECT_EQ(HttpStatusOf(grpc::StatusCode::ALREADY_EXISTS), 409);
  EXPECT_EQ(HttpStatusOf(grpc::StatusCode::FAILED_PRECONDITION), 400);
  EXPECT_EQ(HttpStatusOf(grpc::StatusCode::UNIMPLEMENTED), 501);
  EXPECT_EQ(HttpStatusOf(grpc::StatusCode::UNAVAILABLE), 503);
  const HttpError unimplemented = ToHttpError(grpc::Status(grpc::StatusCode::UNIMPLEMENTED, ""), "x.Y.Z");
  EXPECT_THAT(unimplemented.json_body, HasSubstr("x.Y.Z is not implemented yet"));
}

}  // namespace
}  // namespace insdiag::server
