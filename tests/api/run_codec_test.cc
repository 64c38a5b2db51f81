#include "insdiag/api/run_codec.h"

#include <gtest/gtest.h>

#include "insdiag/api/json.h"
#include "support/synthetic_run.h"

namespace insdiag::api {
namespace {

engine::ImuSample SpecExampleSample() {
  // The first data row of shared/spec/bench-run-format.md.
  return {.t_s = 0.01,
          .gyro_rad_s = {1.1e-05, -2.3e-06, -5.9e-05},
          .acc_mps2 = {0.0012, -0.0007, -9.8154},
          .ref_rpy_rad = {0.0, 0.0, 0.0},
          .temp_degc = 24.1};
}

// Expected digests computed independently:
//   hashlib.sha256(struct.pack('<10d', *values)).hexdigest()
TEST(SampleDigest, IsSha256OfLittleEndianDoublesInColumnOrder) {
  SampleDigest without_temperature(false);
  without_temperature.Add(SpecExampleSample());
  EXPECT_EQ(without_temperature.HexDigest(), "b463ad870efdd6ff9f3cd2547f4709ff14c643f1a003faf03e7c5e212026cd43");
  SampleDigest with_temperature(true);
  with_temperature.Add(SpecExampleSample());
  EXPECT_EQ(with_temperature.HexDigest(), "1e9098d7c39efd0fa8b473cfbc63d4e78753a4fd82115fba506f81def2a8d777");
  EXPECT_EQ(SampleDigest(true).HexDigest(), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
}

TEST(UploadRequests, CarryMetadataChunksAndDigestInOrder) {
  const auto run = testing::SyntheticStaticRun(25, 50.0, 3);
  std::vector<v1::UploadRunRequest> sent;
  ASSERT_TRUE(ForEachUploadRequest(run, "req-7", 10, [&](const v1::UploadRunRequest& request) {
    sent.push_back(request);
    return true;
  }));
  ASSERT_EQ(sent.size(), 5u);  // metadata, 10 + 10 + 5 samples, digest
  EXPECT_EQ(sent[0].metadata().request_id(), "req-7");
  EXPECT_TRUE(sent[0].metadata().has_temperature());
  EXPECT_EQ(sent[3].samples().samples_size(), 5);
  EXPECT_EQ(sent[4].sha256(), SampleSha256(run));

  engine::BenchRun back;
  back.metadata = FromProto(sent[0].metadata());
  EXPECT_NEAR(back.metadata.site.latitude_rad, run.metadata.site.latitude_rad, 1e-15);
  EXPECT_EQ(back.metadata.datasheet, run.metadata.datasheet);
  EXPECT_EQ(back.metadata.extra, run.metadata.extra);
  EXPECT_EQ(FromProto(sent[2].samples().samples(0)).acc_mps2, run.samples[10].acc_mps2);
}

TEST(UploadRequests, StopWhenTheStreamBreaks) {
  const auto run = testing::SyntheticStaticRun(25, 50.0, 3);
  int calls = 0;
  EXPECT_FALSE(ForEachUploadRequest(run, "", 10, [&](const v1::UploadRunRequest&) { return ++calls < 2; }));
  EXPECT_EQ(calls, 2);
}

TEST(Json, PrintsDefaultsAndLowerCamelCaseAndRefusesUnknownFields) {
  v1::Run run;
  run.set_name("runs/x");
  auto json = ToJson(run);
  ASSERT_TRUE(json.ok());
  EXPECT_NE(json->find("\"sampleCount\":\"0\""), std::string::npos) << *json;
  EXPECT_NE(json->find("\"nominalIntervalS\":0"), std::string::npos) << *json;

  v1::Run parsed;
  EXPECT_TRUE(FromJson(R"({"name":"runs/y","sampleCount":"3"})", &parsed).ok());
  EXPECT_EQ(parsed.sample_count(), 3);
  EXPECT_EQ(FromJson(R"({"nope":1})", &parsed).code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace insdiag::api
