// The local loop a factory script walks with the `insdiag` binary
// (shared/spec/cli-and-report.md): simulate a run with a hidden effect,
// `analyze` it, read the ranked candidates, `--add` the first and see the
// error fall. No server: the verbs run the engine in process.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "insdiag/api/json.h"
#include "insdiag/v1/analyses.pb.h"
#include "support/subprocess.h"

namespace insdiag::testing {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;

// A misalignment of the z accelerometer towards x, four INS-2000 tolerances
// (data/unit-types/INS-2000.json: 5e-5 rad), on the tilt profile. The table's
// outer axis is vertical, so with the 45° mount f_y = −f_x in every position:
// the run sees acc_misalignment.zx and .zy only together
// (docs/EFFECT_FINDER_SCENARIOS.md, section 4), and the report must say so.
constexpr char kHidden[] = "acc_misalignment.zx";
constexpr char kTwin[] = "acc_misalignment.zy";
constexpr double kHiddenRad = 4 * 5e-5;

TEST(CliLoopTest, AnalyzeNamesTheAmbiguityAndAddingTheEffectFitsTheRun) {
  const auto dir = MakeTempDir("insdiag-cli-loop");
  const std::string run = (dir / "run.csv").string();
  auto simulated = RunToCompletion({INSDIAG_CLI_PATH, "simulate", run, "--profile", "positions", "--rate", "10",
                                    "--seed", "76", "--effect", std::string(kHidden) + "=" + std::to_string(kHiddenRad)},
                                   dir, 120s);
  ASSERT_TRUE(simulated.ok() && simulated->exit_status == 0) << (simulated.ok() ? simulated->stderr_text : "");

  // Model A, as text: the two terms first, each naming the other.
  auto text = RunToCompletion({INSDIAG_CLI_PATH, "analyze", run}, dir, 300s);
  ASSERT_TRUE(text.ok()) << text.status();
  ASSERT_EQ(text->exit_status, 0) << text->stderr_text;
  EXPECT_THAT(text->stdout_text, HasSubstr("missing effects, most significant first:"));
  EXPECT_THAT(text->stdout_text, HasSubstr(std::string("not told apart in this run from: ") + kTwin));
  EXPECT_THAT(text->stdout_text, HasSubstr(std::string("not told apart in this run from: ") + kHidden));

  // Model B = A + the hidden term, as JSON (insdiag.v1.AnalysisReport).
  auto added = RunToCompletion({INSDIAG_CLI_PATH, "analyze", run, "--add", kHidden, "--json"}, dir, 300s);
  ASSERT_TRUE(added.ok()) << added.status();
  ASSERT_EQ(added->exit_status, 0) << added->stderr_text;
  v1::AnalysisReport b;
  ASSERT_TRUE(api::FromJson(added->stdout_text, &b).ok()) << added->stdout_text.substr(0, 400);
  ASSERT_TRUE(b.has_comparison());
  EXPECT_THAT(b.comparison().added_effects(), ::testing::ElementsAre(kHidden));
  EXPECT_LT(b.comparison().aic_after(), b.comparison().aic_before());
  EXPECT_GE(b.nis_mean(), b.nis_band_low());
  EXPECT_LE(b.nis_mean(), b.nis_band_high());
  // The term's estimate is the truth within 3 of its standard errors, and
  // nothing else is left significant at the family-wise 1 %.
  bool reported = false;
  for (const auto& p : b.identified()) {
    if (p.name() != kHidden) continue;
    reported = true;
    EXPECT_LE(std::abs(p.value() - kHiddenRad), 3.0 * p.std_error()) << p.value() << " ± " << p.std_error();
  }
  EXPECT_TRUE(reported) << "no estimate of " << kHidden << " in identified[]";
  for (const auto& c : b.effect_candidates()) {
    EXPECT_FALSE(c.identifiable() && c.p_value_holm() < 0.01) << c.name() << " still significant";
  }
}

}  // namespace
}  // namespace insdiag::testing
