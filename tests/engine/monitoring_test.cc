// The monitor's promise to a healthy unit: with innovations that match their
// predicted variances, the verdict is GOOD with probability ≥ 1 − α. Checked
// on innovation sequences drawn directly, so that the tests' thresholds, not
// the filter, are what is measured.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "insdiag/engine/filter/observation.h"
#include "insdiag/engine/model/error_model.h"
#include "insdiag/engine/monitor/monitoring.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine {
namespace {

// A forward pass whose innovations are N(0, S) with S fixed per channel,
// one update per channel per second, and a smoother that adds nothing. The
// attitude channels are observed as on a table that holds each position for
// half a minute and turns for a minute between them (ν = S = 0 while it
// turns), with variances as small as an exactly read table's.
struct HealthyInnovations {
  ForwardPass forward;
  SmoothedPass smoothed;
};

constexpr int kHoldEpochs = 30;
constexpr int kPositionCycleEpochs = 90;

HealthyInnovations DrawHealthyInnovations(int epochs, const StateLayout& layout, std::mt19937_64& rng) {
  HealthyInnovations out;
  ForwardPass& fw = out.forward;
  fw.epoch_time_s.resize(static_cast<size_t>(epochs));
  fw.epoch_start_s.resize(static_cast<size_t>(epochs));
  fw.z.resize(epochs, kChannelCount);
  fw.innovation.resize(epochs, kChannelCount);
  fw.innovation_variance.resize(epochs, kChannelCount);
  std::normal_distribution<double> standard;
  for (int k = 0; k < epochs; ++k) {
    fw.epoch_time_s[static_cast<size_t>(k)] = k + 1.0;
    fw.epoch_start_s[static_cast<size_t>(k)] = k;
    const bool table_still = k % kPositionCycleEpochs < kHoldEpochs;
    for (int c = 0; c < kChannelCount; ++c) {
      const bool observed = !IsAttitudeChannel(c) || table_still;
      // The channels' units differ.
      const double variance = !observed ? 0.0 : IsAttitudeChannel(c) ? 1e-20 * std::pow(10.0, -c) : std::pow(10.0, -c);
      fw.innovation_variance(k, c) = variance;
      fw.innovation(k, c) = std::sqrt(variance) * standard(rng);
      fw.z(k, c) = fw.innovation(k, c);
      if (observed) ++fw.scalar_updates;
    }
  }
  out.smoothed.discrepancy = Eigen::MatrixXd::Zero(epochs, layout.size());
  return out;
}

// The moving-window F test is run at every epoch. Its family-wise threshold
// must count the overlapping windows as the tests they are: counting only
// the run's disjoint windows let healthy units be judged FAULTY at about ten
// times the stated rate.
TEST(Monitor, JudgesHealthyInnovationsFaultyNoMoreOftenThanItsFamilyWiseLevel) {
  const StateLayout layout(ErrorModel{});
  MonitorOptions options;
  options.family_wise_alpha = 0.05;  // large enough that a wrong level shows in a few hundred runs
  options.max_localised_failures = 0;
  constexpr int kRuns = 400;
  constexpr int kEpochs = 3300;  // a 55-minute run, one update a second
  std::mt19937_64 rng(20261125);
  int gradual = 0;
  for (int run = 0; run < kRuns; ++run) {
    const HealthyInnovations pass = DrawHealthyInnovations(kEpochs, layout, rng);
    const MonitorResult result = Monitor(pass.forward, pass.smoothed, layout, {}, options);
    for (const FaultInterval& f : result.faults) {
      if (f.kind == FaultKind::kGradual) {
        ++gradual;
        break;
      }
    }
  }
  // The gradual test's share of α is α/3 ≈ 1.7 %: 6.7 runs of 400 at most on
  // average. P(X ≥ 15) < 0.5 % for X ~ Binomial(400, 1/60); the disjoint-window
  // count failed it, with 50 of the 400 runs.
  const double share = options.family_wise_alpha / 3.0;
  const double p_at_least = 1.0 - [&] {
    double cdf = 0.0, term = std::pow(1.0 - share, kRuns);
    for (int x = 0; x < 15; ++x) {
      cdf += term;
      term *= (kRuns - x) / (x + 1.0) * share / (1.0 - share);
    }
    return cdf;
  }();
  ASSERT_LT(p_at_least, 0.005);
  const HealthyInnovations sample = DrawHealthyInnovations(kEpochs, layout, rng);
  const MonitorResult one = Monitor(sample.forward, sample.smoothed, layout, {}, options);
  const int still_epochs = (kEpochs / kPositionCycleEpochs) * kHoldEpochs +
                           std::min(kEpochs % kPositionCycleEpochs, kHoldEpochs);
  EXPECT_EQ(one.channels[kVelocityChannel].count, kEpochs);
  EXPECT_EQ(one.channels[kAttitudeChannel].count, still_epochs);
  EXPECT_LT(gradual, 15) << gradual << " of " << kRuns << " healthy runs had a GRADUAL interval";
}

// The threshold still sees a real change: the residual variance doubled for
// ten minutes mid-run is a gradual failure on that channel.
TEST(Monitor, FindsAResidualVarianceThatDoublesForTenMinutes) {
  const StateLayout layout(ErrorModel{});
  MonitorOptions options;
  options.max_localised_failures = 0;
  std::mt19937_64 rng(7);
  int found = 0;
  constexpr int kRuns = 20;
  for (int run = 0; run < kRuns; ++run) {
    HealthyInnovations pass = DrawHealthyInnovations(3300, layout, rng);
    for (int k = 1500; k < 2100; ++k) pass.forward.innovation(k, 3) *= std::sqrt(2.0);
    const MonitorResult result = Monitor(pass.forward, pass.smoothed, layout, {}, options);
    for (const FaultInterval& f : result.faults) {
      if (f.kind == FaultKind::kGradual && f.channel == "vel_n" && f.end_s > 1500.0 && f.start_s < 2100.0) {
        ++found;
        break;
      }
    }
  }
  EXPECT_GE(found, 19) << "found in " << found << " of " << kRuns;
}

}  // namespace
}  // namespace insdiag::engine
