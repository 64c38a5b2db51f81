// ParallelMap: results in index order whatever the schedule, and a map
// inside a map runs on its caller's thread; tasks alongside each other.
#include "insdiag/engine/numerics/parallel_map.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <vector>

namespace insdiag::engine::numerics {
namespace {

// Uneven work per index, so that the workers finish out of order.
double Work(std::size_t i) {
  double x = static_cast<double>(i);
  for (std::size_t k = 0; k < (i % 7) * 2000; ++k) x = std::sqrt(x * x + 1.0);
  return x;
}

TEST(ParallelMap, ReturnsEachIndexResultInIndexOrderAsASerialLoopDoes) {
  for (std::size_t n : {0u, 1u, 7u, 1000u}) {
    std::vector<double> serial;
    for (std::size_t i = 0; i < n; ++i) serial.push_back(Work(i));
    EXPECT_EQ(ParallelMap(n, Work), serial) << "n = " << n;
  }
}

TEST(ParallelMap, AMapInsideAMapGivesTheSameResults) {
  const auto outer = ParallelMap(8, [](std::size_t i) {
    const auto inner = ParallelMap(50, [i](std::size_t j) { return Work(i * 50 + j); });
    double sum = 0.0;
    for (double v : inner) sum += v;
    return sum;
  });
  for (std::size_t i = 0; i < 8; ++i) {
    double sum = 0.0;
    for (std::size_t j = 0; j < 50; ++j) sum += Work(i * 50 + j);
    EXPECT_EQ(outer[i], sum) << i;
  }
}

// Two tasks alongside each other, each with a map inside: both run to the
// end, and each gets the results of its serial loop.
TEST(ParallelMap, TasksAlongsideEachOtherGiveTheirSerialResults) {
  std::vector<double> first, second;
  AlongsideEachOther(
      [&] { first = ParallelMap(300, Work); },
      [&] { second = ParallelMap(200, [](std::size_t i) { return Work(i + 300); }); });
  std::vector<double> serial;
  for (std::size_t i = 0; i < 500; ++i) serial.push_back(Work(i));
  EXPECT_EQ(first, std::vector<double>(serial.begin(), serial.begin() + 300));
  EXPECT_EQ(second, std::vector<double>(serial.begin() + 300, serial.end()));
}

TEST(ParallelMap, UsesAtLeastOneThread) { EXPECT_GE(WorkerThreads(), 1); }

}  // namespace
}  // namespace insdiag::engine::numerics
