// The decimation of residual series for display (server/display_series.h).
#include "insdiag/server/display_series.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace insdiag::server {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

// Epochs every `dt` s from t = 0: residual = sin, a one-epoch spike at `spike_at`.
std::vector<SeriesEpoch> Series(int count, double dt, int spike_at = -1) {
  std::vector<SeriesEpoch> epochs;
  for (int k = 0; k < count; ++k) {
    const double t = k * dt;
    const double residual = std::sin(0.01 * k) + (k == spike_at ? 50.0 : 0.0);
    epochs.push_back({t, 10.0 + residual, 10.0, residual, 3.0 + 0.001 * k});
  }
  return epochs;
}

TEST(DisplaySeriesTest, FewEpochsComeBackAsTheyAre) {
  const auto epochs = Series(10, 1.0);
  auto out = DecimateForDisplay(epochs, 0.0, 9.0, 100);
  ASSERT_TRUE(out.ok()) << out.status();
  EXPECT_FALSE(out->decimated());
  EXPECT_EQ(out->epochs(), 10);
  ASSERT_EQ(out->t_size(), 10);
  for (int k = 0; k < 10; ++k) {
    EXPECT_EQ(out->t(k), epochs[k].t);
    EXPECT_EQ(out->residual_min(k), epochs[k].residual);
    EXPECT_EQ(out->residual_max(k), epochs[k].residual);
    EXPECT_EQ(out->band_low(k), epochs[k].predicted - epochs[k].sigma3);
    EXPECT_EQ(out->band_high(k), epochs[k].predicted + epochs[k].sigma3);
  }
}

TEST(DisplaySeriesTest, ALongSeriesShrinksToOneEnvelopePerColumnAndKeepsItsExtremes) {
  // 100,000 epochs, a one-epoch spike in the middle, 800 columns.
  const auto epochs = Series(100'000, 0.1, 50'001);
  auto out = DecimateForDisplay(epochs, epochs.front().t, epochs.back().t, 800);
  ASSERT_TRUE(out.ok()) << out.status();
  EXPECT_TRUE(out->decimated());
  EXPECT_EQ(out->epochs(), 100'000);
  EXPECT_EQ(out->t_size(), 800);
  double highest = -1e300, lowest = 1e300, widest = 0;
  for (int c = 0; c < out->t_size(); ++c) {
    EXPECT_LE(out->residual_min(c), out->residual_max(c));
    EXPECT_LE(out->band_low(c), out->band_high(c));
    if (c > 0) {
      EXPECT_LT(out->t(c - 1), out->t(c));
    }
    highest = std::max(highest, out->residual_max(c));
    lowest = std::min(lowest, out->residual_min(c));
    widest = std::max(widest, out->sigma3_max(c));
  }
  // The spike (one epoch in 100,000) reaches its full height on the plot.
  EXPECT_DOUBLE_EQ(highest, epochs[50'001].residual);
  double true_lowest = 1e300;
  for (const auto& e : epochs) true_lowest = std::min(true_lowest, e.residual);
  EXPECT_DOUBLE_EQ(lowest, true_lowest);
  EXPECT_DOUBLE_EQ(widest, epochs.back().sigma3);
}

TEST(DisplaySeriesTest, EachColumnHoldsTheExtremesOfItsOwnEpochs) {
  // 20 epochs at t = 0 … 19 into 4 columns of 19/4 s.
  const auto epochs = Series(20, 1.0);
  auto out = DecimateForDisplay(epochs, 0.0, 19.0, 4);
  ASSERT_TRUE(out.ok()) << out.status();
  ASSERT_EQ(out->t_size(), 4);
  const double width = 19.0 / 4;
  for (int c = 0; c < 4; ++c) {
    EXPECT_DOUBLE_EQ(out->t(c), (c + 0.5) * width);
    double low = 1e300, high = -1e300, band_low = 1e300, band_high = -1e300;
    for (const auto& e : epochs) {
      const int column = std::min(3, static_cast<int>(e.t / width));  // t = 19 belongs to the last column
      if (column != c) continue;
      low = std::min(low, e.residual);
      high = std::max(high, e.residual);
      band_low = std::min(band_low, e.predicted - e.sigma3);
      band_high = std::max(band_high, e.predicted + e.sigma3);
    }
    EXPECT_DOUBLE_EQ(out->residual_min(c), low) << "column " << c;
    EXPECT_DOUBLE_EQ(out->residual_max(c), high) << "column " << c;
    EXPECT_DOUBLE_EQ(out->band_low(c), band_low) << "column " << c;
    EXPECT_DOUBLE_EQ(out->band_high(c), band_high) << "column " << c;
  }
}

TEST(DisplaySeriesTest, AZoomedRangeTakesOnlyItsEpochsAndGetsFinerData) {
  const auto epochs = Series(100'000, 0.1);  // 0 … 9999.9 s
  auto whole = DecimateForDisplay(epochs, 0.0, 9999.9, 500);
  auto zoomed = DecimateForDisplay(epochs, 1000.0, 1030.0, 500);  // 301 epochs
  ASSERT_TRUE(whole.ok() && zoomed.ok());
  EXPECT_TRUE(whole->decimated());
  EXPECT_FALSE(zoomed->decimated());
  EXPECT_EQ(zoomed->epochs(), 301);
  EXPECT_DOUBLE_EQ(zoomed->t(0), 1000.0);
  EXPECT_NEAR(zoomed->t(zoomed->t_size() - 1), 1030.0, 1e-9);
}

TEST(DisplaySeriesTest, EmptyColumnsAreLeftOut) {
  // Epochs only in the first and last second of a 100 s range.
  std::vector<SeriesEpoch> epochs;
  for (int k = 0; k < 10; ++k) epochs.push_back({0.1 * k, 1, 1, 0, 1});
  for (int k = 0; k < 10; ++k) epochs.push_back({99.0 + 0.1 * k, 1, 1, 0, 1});
  auto out = DecimateForDisplay(epochs, 0.0, 100.0, 10);
  ASSERT_TRUE(out.ok());
  EXPECT_TRUE(out->decimated());
  EXPECT_THAT(out->t(), ElementsAre(5.0, 95.0));
}

TEST(DisplaySeriesTest, RefusesNoColumnsAndBackwardRanges) {
  const auto epochs = Series(10, 1.0);
  EXPECT_THAT(DecimateForDisplay(epochs, 0, 9, 0).status().message(), HasSubstr("columns"));
  EXPECT_FALSE(DecimateForDisplay(epochs, 9, 0, 10).ok());
  EXPECT_FALSE(DecimateForDisplay(epochs, 0, NAN, 10).ok());
}

}  // namespace
}  // namespace insdiag::server
