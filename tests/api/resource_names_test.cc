// The v1 API's resource names (proto/include/insdiag/api/resource_names.h).
#include "insdiag/api/resource_names.h"

#include <gtest/gtest.h>

namespace insdiag::api {
namespace {

TEST(ResourceNamesTest, ANameIsItsCollectionAndItsId) {
  EXPECT_EQ(ResourceName(kRuns, "abc"), "runs/abc");
  EXPECT_EQ(ResourceName(kUnitTypes, "INS-2000"), "unitTypes/INS-2000");
  auto id = ResourceId("analyses/0f3a", kAnalyses);
  ASSERT_TRUE(id.ok()) << id.status();
  EXPECT_EQ(*id, "0f3a");
  EXPECT_EQ(*ResourceId(ResourceName(kFailureRecords, "r1"), kFailureRecords), "r1");
}

TEST(ResourceNamesTest, AnythingElseIsRefusedNamingTheFieldAndThePattern) {
  for (const char* bad : {"", "runs", "runs/", "runs/a/b", "analyses/a", "run/a", "runsa", "/runs/a"}) {
    auto id = ResourceId(bad, kRuns, "analysis.run");
    ASSERT_FALSE(id.ok()) << bad;
    EXPECT_EQ(id.status().code(), absl::StatusCode::kInvalidArgument) << bad;
    EXPECT_EQ(id.status().message(),
              std::string("analysis.run: '") + bad + "' is not a run name (runs/{run})");
  }
  EXPECT_EQ(ResourceId("units/", kUnits).status().message(), "name: 'units/' is not a unit name (units/{unit})");
  EXPECT_EQ(ResourceId("x", kAnalyses).status().message(),
            "name: 'x' is not an analysis name (analyses/{analysis})");
}

TEST(ResourceNamesTest, ABareIdIsAcceptedWhereTheInputAllowsIt) {
  EXPECT_EQ(IdOrSelf("unitTypes/INS-2000", kUnitTypes), "INS-2000");
  EXPECT_EQ(IdOrSelf("INS-2000", kUnitTypes), "INS-2000");
  EXPECT_EQ(IdOrSelf("unitTypes", kUnitTypes), "unitTypes");
}

}  // namespace
}  // namespace insdiag::api
