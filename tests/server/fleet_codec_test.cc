#include "fleet_codec.h"

#include <gtest/gtest.h>

namespace insdiag::server {
namespace {

// A request's times reach the store as whole microseconds, as PostgreSQL
// stores them; an unset time is no filter.
TEST(FleetCodec, RequestTimesAreWholeMicrosecondsAndUnsetIsNone) {
  v1::ListFailureCountsRequest request;
  request.mutable_start_time()->set_seconds(1'700'000'000);
  request.mutable_start_time()->set_nanos(123'456'789);
  const kb::FailureCountQuery query = FromProto(request);
  ASSERT_TRUE(query.start_time.has_value());
  EXPECT_EQ(*query.start_time, absl::FromUnixMicros(1'700'000'000'123'456));
  EXPECT_FALSE(query.end_time.has_value());
}

// Times before 1970 keep a non-negative nanos field (the Timestamp's rule).
TEST(FleetCodec, ResultTimesMapToTimestampsAndAbsentTimesStayUnset) {
  kb::FleetStatistics statistics;
  EXPECT_FALSE(ToProto(statistics).has_counts_time());
  statistics.counts_time = absl::FromUnixMicros(-1);
  const v1::FleetStatistics with_time = ToProto(statistics);
  ASSERT_TRUE(with_time.has_counts_time());
  EXPECT_EQ(with_time.counts_time().seconds(), -1);
  EXPECT_EQ(with_time.counts_time().nanos(), 999'999'000);

  kb::ParameterTrend trend;
  trend.buckets.emplace_back().month = absl::FromUnixSeconds(1'706'745'600);
  const v1::ParameterTrend mapped = ToProto(trend);
  EXPECT_FALSE(mapped.has_refreshed_time());
  ASSERT_EQ(mapped.buckets_size(), 1);
  EXPECT_EQ(mapped.buckets(0).month().seconds(), 1'706'745'600);
  EXPECT_EQ(mapped.buckets(0).month().nanos(), 0);
}

TEST(FleetCodec, PagesCarryTheirSizeAndTokensBothWays) {
  v1::RankUnitsRequest request;
  request.set_page_size(7);
  request.set_page_token("abc");
  const kb::UnitRankingQuery query = FromProto(request);
  EXPECT_EQ(query.page.page_size, 7);
  EXPECT_EQ(query.page.page_token, "abc");

  kb::UnitRankingPage page;
  page.units.emplace_back().unit = "units/INS-0001";
  page.next_page_token = "next";
  const v1::RankUnitsResponse response = ToProto(page);
  ASSERT_EQ(response.units_size(), 1);
  EXPECT_EQ(response.units(0).unit(), "units/INS-0001");
  EXPECT_EQ(response.next_page_token(), "next");
}

}  // namespace
}  // namespace insdiag::server
