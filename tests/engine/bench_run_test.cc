#include "insdiag/engine/bench_run.h"

#include <gtest/gtest.h>

namespace insdiag::engine {
namespace {

BenchRun RunWithTimes(const std::vector<double>& times) {
  BenchRun run;
  for (double t : times) run.samples.push_back(ImuSample{.t_s = t});
  return run;
}

TEST(BenchRun, NominalIntervalIsTheMedianStep) {
  // One late sample must not move the nominal interval.
  const BenchRun run = RunWithTimes({0.01, 0.02, 0.03, 0.05, 0.06, 0.07});
  EXPECT_DOUBLE_EQ(run.NominalIntervalS(), 0.01);
  EXPECT_NEAR(run.DurationS(), 0.07, 1e-12);
}

TEST(BenchRun, ExtraMetadataIsFoundByKey) {
  BenchRunMetadata meta;
  meta.extra = {{"bench", "table-3"}, {"operator", "kim"}};
  EXPECT_EQ(meta.Extra("operator"), "kim");
  EXPECT_FALSE(meta.Extra("notes").has_value());
}

}  // namespace
}  // namespace insdiag::engine
