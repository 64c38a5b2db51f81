// The v1 API's resource names (proto/base/include/insdiag/api/resource_names.h).
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

TEST(ResourceNamesTest, AModuleIsNamedWithinItsUnitByItsRole) {
  EXPECT_EQ(ModuleName("INS-0002", "gyro.x"), "units/INS-0002/modules/gyro.x");
  auto module = ParseModuleName("units/INS-0002/modules/gyro.x");
  ASSERT_TRUE(module.ok()) << module.status();
  EXPECT_EQ(module->unit, "INS-0002");
  EXPECT_EQ(module->role, "gyro.x");
  for (const char* bad : {"", "units/INS-0002", "units//modules/gyro.x", "units/INS-0002/modules/",
                          "units/a/b/modules/gyro.x", "units/a/modules/gyro/x",
                          "unit/a/modules/gyro.x", "units/a/module/gyro.x"}) {
    auto parsed = ParseModuleName(bad, "failure_record.module");
    ASSERT_FALSE(parsed.ok()) << bad;
    EXPECT_EQ(parsed.status().message(),
              std::string("failure_record.module: '") + bad +
                  "' is not a module name (units/{unit}/modules/{module})");
  }
}

}  // namespace
}  // namespace insdiag::api
