// Weibull maximum likelihood with right censoring and MTBF bounds, checked
// against an independent computation: tests/kb/weibull_reference.py (scipy,
// direct Nelder–Mead on the full likelihood), run by this test.
#include "insdiag/kb/reliability.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

namespace insdiag::kb {
namespace {

// Lives drawn from Weibull(shape, scale), censored at a random withdrawal time.
std::vector<LifeObservation> CensoredSample(double shape, double scale, double censor_max, int n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::weibull_distribution<double> life(shape, scale);
  std::uniform_real_distribution<double> withdraw(0.1 * censor_max, censor_max);
  std::vector<LifeObservation> out;
  for (int i = 0; i < n; ++i) {
    const double t = life(rng), c = withdraw(rng);
    out.push_back({std::min(t, c), t <= c});
  }
  return out;
}

struct Reference {
  double shape, scale, b10, mtbf_lower, mtbf_upper;
};

Reference RunReference(const std::vector<LifeObservation>& lives) {
  const auto dir = std::filesystem::temp_directory_path() / ("insdiag-weibull-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto csv = dir / "lives.csv";
  {
    std::ofstream out(csv);
    out.precision(17);
    for (const auto& l : lives) out << l.hours << "," << (l.failed ? 1 : 0) << "\n";
  }
  const std::string command = "/usr/bin/python3 " INSDIAG_SOURCE_DIR "/tests/kb/weibull_reference.py " + csv.string();
  FILE* pipe = popen(command.c_str(), "r");
  EXPECT_NE(pipe, nullptr);
  char buffer[512] = {};
  std::string text;
  while (pipe != nullptr && fgets(buffer, sizeof buffer, pipe) != nullptr) text += buffer;
  const int status = pipe != nullptr ? pclose(pipe) : -1;
  EXPECT_EQ(status, 0) << command << " printed: " << text;
  std::filesystem::remove_all(dir);
  Reference r{};
  std::istringstream in(text);
  in >> r.shape >> r.scale >> r.b10 >> r.mtbf_lower >> r.mtbf_upper;
  return r;
}

TEST(WeibullTest, CensoredFitMatchesScipyWithinOnePercent) {
  for (const auto& [shape, scale, seed] : {std::tuple{2.5, 60000.0, 1u}, std::tuple{1.2, 150000.0, 2u},
                                          std::tuple{3.5, 85000.0, 3u}}) {
    const auto lives = CensoredSample(shape, scale, 80000.0, 2000, seed);
    auto fit = FitWeibull(lives, 0.9);
    ASSERT_TRUE(fit.ok()) << fit.status();
    const Reference ref = RunReference(lives);
    ASSERT_GT(ref.shape, 0.0);
    EXPECT_NEAR(fit->shape, ref.shape, 0.01 * ref.shape) << "seed " << seed;
    EXPECT_NEAR(fit->scale_hours, ref.scale, 0.01 * ref.scale) << "seed " << seed;
    EXPECT_NEAR(fit->b10_hours, ref.b10, 0.01 * ref.b10) << "seed " << seed;
    // And the truth lies within the 90 % bounds (a statistical check: seeded).
    EXPECT_LT(fit->shape_lower, shape);
    EXPECT_GT(fit->shape_upper, shape);
    RecordProperty("shape_" + std::to_string(seed), std::to_string(fit->shape) + " vs scipy " + std::to_string(ref.shape));
    std::printf("seed %u: shape %.6g (scipy %.6g), scale %.6g h (scipy %.6g), B10 %.6g h (scipy %.6g), %lld failures\n",
                seed, fit->shape, ref.shape, fit->scale_hours, ref.scale, fit->b10_hours, ref.b10,
                static_cast<long long>(fit->failures));
  }
}

TEST(WeibullTest, RefusesTooFewFailures) {
  std::vector<LifeObservation> lives = {{100, true}, {200, false}, {300, false}};
  EXPECT_EQ(FitWeibull(lives, 0.9).status().code(), absl::StatusCode::kFailedPrecondition);
  lives = {{100, true}, {-1, true}};
  EXPECT_EQ(FitWeibull(lives, 0.9).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(MtbfTest, ChiSquareBoundsMatchScipy) {
  const auto lives = CensoredSample(1.0, 50000.0, 80000.0, 500, 4);
  double hours = 0.0;
  std::int64_t failures = 0;
  for (const auto& l : lives) {
    hours += l.hours;
    failures += l.failed ? 1 : 0;
  }
  const MtbfEstimate m = EstimateMtbf(hours, failures, 0.9);
  const Reference ref = RunReference(lives);
  EXPECT_NEAR(m.mtbf_hours, hours / static_cast<double>(failures), 1e-9 * hours);
  EXPECT_NEAR(m.lower_hours, ref.mtbf_lower, 1e-6 * ref.mtbf_lower);
  EXPECT_NEAR(m.upper_hours, ref.mtbf_upper, 1e-6 * ref.mtbf_upper);
  EXPECT_EQ(EstimateMtbf(1000.0, 0, 0.9).upper_hours, 0.0);  // unbounded without failures
  EXPECT_GT(EstimateMtbf(1000.0, 0, 0.9).lower_hours, 0.0);
}

}  // namespace
}  // namespace insdiag::kb
