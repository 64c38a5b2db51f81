// The fleet views' scheduled refresh (server/fleet_view_refresher.h) against
// a real PostgreSQL: a unit written after the last refresh reaches the fleet
// counts within a period or two, and none is scheduled when the period is 0.
#include "insdiag/server/fleet_view_refresher.h"

#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <thread>

#include "insdiag/kb/pg.h"
#include "support/database_fixture.h"

namespace insdiag::server {
namespace {

using FleetViewRefresherTest = testing::DatabaseTest;
using namespace std::chrono_literals;

// The units of `unit_type` the fleet counts view holds, "" when it holds none.
std::string CountedUnits(kb::ConnectionPool& pool, const std::string& unit_type) {
  auto db = pool.Acquire();
  EXPECT_TRUE(db.ok()) << db.status();
  auto rows = (*db)->Exec("SELECT units FROM fleet_counts WHERE unit_type = $1", {kb::Param::Text(unit_type)});
  EXPECT_TRUE(rows.ok()) << rows.status();
  return rows.ok() && rows->rows() > 0 ? rows->String(0, 0) : "";
}

void AddUnit(kb::ConnectionPool& pool, const std::string& serial, const std::string& unit_type) {
  auto db = pool.Acquire();
  ASSERT_TRUE(db.ok()) << db.status();
  ASSERT_TRUE((*db)->Exec("INSERT INTO units (serial, unit_type) VALUES ($1, $2)",
                          {kb::Param::Text(serial), kb::Param::Text(unit_type)})
                  .ok());
}

TEST_F(FleetViewRefresherTest, AUnitWrittenAfterTheLastRefreshIsCountedWithinTwoPeriods) {
  constexpr auto kPeriod = 200ms;
  AddUnit(pool(), "REFRESH-1", "INS-REFRESH");
  EXPECT_EQ(CountedUnits(pool(), "INS-REFRESH"), "") << "the view counts what no refresh has read";
  FleetViewRefresher refresher(pool(), kPeriod);
  refresher.Start();
  const auto deadline = std::chrono::steady_clock::now() + 2 * kPeriod + 5s;  // a refresh takes milliseconds
  while (CountedUnits(pool(), "INS-REFRESH") != "1" && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(20ms);
  }
  EXPECT_EQ(CountedUnits(pool(), "INS-REFRESH"), "1");
  const auto stop_start = std::chrono::steady_clock::now();
  refresher.Stop();
  EXPECT_LT(std::chrono::steady_clock::now() - stop_start, kPeriod + 2s) << "Stop waits for no further period";
}

TEST_F(FleetViewRefresherTest, APeriodOfZeroRefreshesNothing) {
  AddUnit(pool(), "REFRESH-2", "INS-NEVER");
  FleetViewRefresher refresher(pool(), 0ms);
  refresher.Start();
  std::this_thread::sleep_for(300ms);
  refresher.Stop();
  EXPECT_EQ(CountedUnits(pool(), "INS-NEVER"), "");
}

}  // namespace
}  // namespace insdiag::server
