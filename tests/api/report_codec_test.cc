#include "insdiag/api/report_codec.h"

#include <gtest/gtest.h>

#include <limits>

namespace insdiag::api {
namespace {

// A candidate no test measured reaches API clients flagged as such, and an
// unknown standard error (infinite in the engine) as 0, which JSON can carry.
TEST(ReportCodec, UntestedCandidateIsFlaggedAndItsUnknownErrorIsFinite) {
  engine::AnalysisReport report;
  engine::EffectCandidate untested;
  untested.name = "gyro_bias_second_order.z";
  untested.source = "LIKELIHOOD";
  untested.tested = false;
  untested.std_error = std::numeric_limits<double>::infinity();
  untested.note = "not tested on this model: a constant term is significant";
  engine::EffectCandidate tested;
  tested.name = "gyro_scale_factor.z";
  tested.source = "SCORE";
  tested.estimate = 2e-4;
  tested.std_error = 2e-5;
  report.effect_candidates = {untested, tested};
  const v1::AnalysisReport out = ToProto(report, engine::ErrorModel{});
  ASSERT_EQ(out.effect_candidates_size(), 2);
  EXPECT_TRUE(out.effect_candidates(0).not_tested());
  EXPECT_EQ(out.effect_candidates(0).std_error(), 0.0);
  EXPECT_EQ(out.effect_candidates(0).note(), untested.note);
  EXPECT_FALSE(out.effect_candidates(1).not_tested());
  EXPECT_EQ(out.effect_candidates(1).std_error(), 2e-5);
}

}  // namespace
}  // namespace insdiag::api
