// A job's spec as the engine's request (server/analysis_job.h), and which
// failures another attempt may meet.
#include "insdiag/server/analysis_job.h"

#include <gtest/gtest.h>

#include "insdiag/engine/model/parameters.h"

namespace insdiag::server {
namespace {

v1::AnalysisSpec Spec() {
  v1::AnalysisSpec spec;
  spec.mutable_model()->add_effects("gyro_scale_factor.z");
  spec.mutable_baseline()->add_effects("acc_bias_step.x@1500");
  return spec;
}

TEST(EngineRequestOf, CarriesTheEffectsToAddModelAsBaselineAndTheLoop) {
  v1::AnalysisSpec spec = Spec();
  spec.set_discover(true);
  auto request = EngineRequestOf(spec, std::nullopt, nullptr);
  ASSERT_TRUE(request.ok()) << request.status();
  EXPECT_EQ(request->add_effects, std::vector<std::string>{"gyro_scale_factor.z"});
  EXPECT_EQ(request->baseline_effects, std::vector<std::string>{"acc_bias_step.x@1500"});
  EXPECT_TRUE(request->discover);
  EXPECT_FALSE(request->nominal.has_value()) << "no nominal model and no override: the engine identifies";
  EXPECT_FALSE(request->identified_base.has_value());
}

TEST(EngineRequestOf, SetsTheSpecsParametersOnTheNominalModelOrOnADefaultOne) {
  v1::AnalysisSpec spec = Spec();
  auto* p = spec.mutable_model()->add_parameters();
  p->set_name("gyro_bias_gm.x.tau");
  p->set_value(1234.0);
  engine::ErrorModel nominal;
  nominal.gyro.bias[1].tau_s = 777.0;
  for (const std::optional<engine::ErrorModel>& given : {std::optional<engine::ErrorModel>(nominal),
                                                         std::optional<engine::ErrorModel>()}) {
    auto request = EngineRequestOf(spec, given, nullptr);
    ASSERT_TRUE(request.ok()) << request.status();
    ASSERT_TRUE(request->nominal.has_value());
    EXPECT_EQ(request->nominal->gyro.bias[0].tau_s, 1234.0);
    if (given.has_value()) {
      EXPECT_EQ(request->nominal->gyro.bias[1].tau_s, 777.0) << "the rest of the nominal model kept";
    }
  }
}

TEST(EngineRequestOf, RefusesAParameterTheEngineDoesNotKnowNamingTheField) {
  v1::AnalysisSpec spec = Spec();
  spec.mutable_model()->add_parameters()->set_name("gyro_bias_gm.w.tau");
  auto request = EngineRequestOf(spec, std::nullopt, nullptr);
  ASSERT_EQ(request.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(request.status().message().find("analysis.model.parameters"), std::string::npos) << request.status();
  EXPECT_FALSE(Retryable(request.status())) << "a refused input fails the job at once";
}

TEST(Retryable, OnlyWhatTheInputCannotCause) {
  EXPECT_TRUE(Retryable(absl::UnavailableError("the database is away")));
  EXPECT_TRUE(Retryable(absl::InternalError("the engine failed")));
  EXPECT_FALSE(Retryable(absl::NotFoundError("runs/x")));
  EXPECT_FALSE(Retryable(absl::FailedPreconditionError("too short")));
  EXPECT_FALSE(Retryable(absl::OutOfRangeError("beyond the run")));
}

}  // namespace
}  // namespace insdiag::server
