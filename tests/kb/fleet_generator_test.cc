// The fleet generator against a real PostgreSQL: a small generated fleet is
// consistent (every failure record's module was installed when it was
// detected, lives are censored where they should be, the counts are what the
// generator says), deterministic for a seed, readable through the stores (a
// generated analysis has a report, every unit a diagnosis), and every fleet
// statistic answers over it.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "analysis_codec.h"
#include "evidence_reports.h"
#include "insdiag/api/resource_names.h"
#include "insdiag/kb/analysis_store.h"
#include "insdiag/kb/diagnosis_store.h"
#include "insdiag/kb/fleet_generator.h"
#include "insdiag/kb/fleet_store.h"
#include "support/database_fixture.h"

namespace insdiag::kb {
namespace {

using ::testing::HasSubstr;

constexpr std::int64_t kEndTime = 1'748'736'000'000'000;  // 2025-06-01T00:00:00Z

FleetGeneratorOptions SmallFleet() {
  FleetGeneratorOptions options;
  options.units = 50;
  options.seed = 11;
  options.end_time_micros = kEndTime;
  return options;
}

std::int64_t Count(Connection& db, const std::string& sql) {
  auto rows = db.Exec(sql);
  EXPECT_TRUE(rows.ok()) << rows.status() << " " << sql;
  if (!rows.ok()) return -1;
  auto value = rows->Int(0, 0);
  return value.ok() ? *value : -1;
}

class FleetGeneratorTest : public insdiag::testing::DatabaseTest {
 protected:
  GeneratedFleet Generate(const FleetGeneratorOptions& options) {
    auto fleet = GenerateFleet(pool(), options, [](const std::string&) {});
    EXPECT_TRUE(fleet.ok()) << fleet.status();
    return fleet.ok() ? *fleet : GeneratedFleet{};
  }
};

TEST_F(FleetGeneratorTest, WritesAConsistentFleetWithTheCountsItReports) {
  const GeneratedFleet fleet = Generate(SmallFleet());
  ASSERT_EQ(fleet.units, 50);
  auto lease = pool().Acquire();
  ASSERT_TRUE(lease.ok());
  Connection& db = **lease;
  EXPECT_EQ(Count(db, "SELECT count(*) FROM units"), fleet.units);
  EXPECT_EQ(Count(db, "SELECT count(*) FROM modules"), fleet.modules);
  EXPECT_EQ(Count(db, "SELECT count(*) FROM runs"), fleet.runs);
  EXPECT_EQ(Count(db, "SELECT count(*) FROM analyses WHERE state = 'SUCCEEDED'"), fleet.analyses);
  EXPECT_EQ(Count(db, "SELECT count(*) FROM identified_parameters"), fleet.identified_parameters);
  EXPECT_EQ(Count(db, "SELECT count(*) FROM failure_records WHERE confirmed"), fleet.confirmed_failures);
  EXPECT_EQ(Count(db, "SELECT count(*) FROM failure_records WHERE no_fault_found"), fleet.no_fault_found);
  EXPECT_EQ(Count(db, "SELECT count(*) FROM failure_records WHERE censored"), fleet.censored_records);
  EXPECT_EQ(Count(db, "SELECT count(*) FROM diagnoses"), fleet.diagnoses);
  EXPECT_GT(fleet.confirmed_failures, 0);
  EXPECT_GT(fleet.no_fault_found, 0);
  EXPECT_GT(fleet.analyses, 10 * fleet.units);  // quarterly tests over years

  // Every record's module was installed (and not yet removed) when the
  // record's event happened, and the hours agree with the installation.
  EXPECT_EQ(Count(db,
                  "SELECT count(*) FROM failure_records r JOIN modules m USING (module_id) WHERE r.unit_id <> m.unit_id "
                  "OR r.detected_time < m.installed_time OR r.detected_time > coalesce(m.removed_time, 'infinity') "
                  "OR r.operating_hours < m.installed_hours - 1e-6 "
                  "OR r.operating_hours > coalesce(m.removed_hours, 'infinity') + 1e-6"),
            0);
  // A confirmed failure ends its part's life: the part is removed there, and
  // a new part takes the role at the same hours.
  EXPECT_EQ(Count(db,
                  "SELECT count(*) FROM failure_records r JOIN modules m USING (module_id) WHERE r.confirmed AND "
                  "(m.removed_time IS DISTINCT FROM r.detected_time OR m.removal_reason <> 'failed: ' || r.failure_mode "
                  "OR NOT EXISTS (SELECT 1 FROM modules n WHERE n.unit_id = m.unit_id AND n.role = m.role "
                  "AND n.installed_time = m.removed_time AND n.installed_hours = m.removed_hours))"),
            0);
  EXPECT_EQ(Count(db, "SELECT count(*) FROM modules WHERE removal_reason LIKE 'failed: %'"), fleet.confirmed_failures);
  // Censoring: a part is removed only by its failure or its unit's withdrawal;
  // every unit in service has one current part per role, a withdrawn unit none.
  EXPECT_EQ(Count(db,
                  "SELECT count(*) FROM modules m JOIN units u USING (unit_id) WHERE m.removal_reason = 'unit retired' "
                  "AND (u.retired_time IS NULL OR m.removed_time <> u.retired_time OR m.removed_hours <> "
                  "u.operating_hours)"),
            0);
  EXPECT_EQ(Count(db, "SELECT count(*) FROM modules m JOIN units u USING (unit_id) WHERE m.removed_time IS NULL "
                      "AND u.retired_time IS NOT NULL"),
            0);
  EXPECT_EQ(Count(db, "SELECT count(*) FROM modules WHERE removed_time IS NULL"),
            Count(db, "SELECT count(*) FROM units WHERE retired_time IS NULL") *
                Count(db, "SELECT count(*) FROM module_roles"));
  EXPECT_EQ(Count(db, "SELECT count(*) FROM failure_records WHERE censored"),
            Count(db, "SELECT count(*) FROM modules WHERE removal_reason = 'unit retired'"));
  // Nothing happens after the present or before commissioning.
  EXPECT_EQ(Count(db, "SELECT count(*) FROM analyses a JOIN units u USING (unit_id) WHERE a.create_time > "
                      "'2025-06-01T00:00:00Z' OR a.create_time < u.commission_time "
                      "OR a.create_time > coalesce(u.retired_time, 'infinity') OR a.unit_hours > u.operating_hours + 1e-6"),
            0);
  // Every analysis carries the unit type's identified parameters; every
  // unit's latest analysis is diagnosed, and the failures' diagnoses are
  // resolved by their records.
  EXPECT_EQ(Count(db, "SELECT count(*) FROM (SELECT analysis_id FROM identified_parameters GROUP BY 1 "
                      "HAVING count(*) = (SELECT count(*) FROM nominal_parameters WHERE value > 0)) s"),
            fleet.analyses);
  EXPECT_EQ(Count(db, "SELECT count(*) FROM units u WHERE NOT EXISTS (SELECT 1 FROM diagnoses d JOIN analyses a "
                      "USING (analysis_id) WHERE d.unit_id = u.unit_id AND a.create_time = (SELECT max(create_time) "
                      "FROM analyses WHERE unit_id = u.unit_id))"),
            0);
  EXPECT_EQ(Count(db, "SELECT count(*) FROM failure_records r JOIN diagnoses d USING (diagnosis_id) "
                      "WHERE d.record_id = r.record_id AND d.analysis_id = r.analysis_id"),
            fleet.confirmed_failures + fleet.no_fault_found);
  // The foreign keys are back in place.
  EXPECT_EQ(Count(db, "SELECT count(*) FROM pg_constraint WHERE contype = 'f' AND conrelid = "
                      "'identified_parameters'::regclass"),
            2);
}

TEST_F(FleetGeneratorTest, TheSameSeedGivesTheSameFleetAndAnotherSeedAnother) {
  const std::string fingerprint =
      "SELECT md5(string_agg(u.serial || u.batch || u.operating_hours::text || coalesce(r.failure_mode, '') || "
      "r.operating_hours::text, ',' ORDER BY u.serial, r.detected_time, r.failure_mode)) || "
      "(SELECT sum(value::numeric)::text FROM identified_parameters) FROM units u LEFT JOIN failure_records r USING (unit_id)";
  Generate(SmallFleet());
  auto first = (*pool().Acquire())->Exec(fingerprint);
  ASSERT_TRUE(first.ok()) << first.status();

  auto other = insdiag::testing::ScratchDatabase::Create();
  ASSERT_TRUE(other.ok());
  auto other_pool = ConnectionPool::Create({.database_url = (*other)->url(), .max_connections = 2});
  ASSERT_TRUE(other_pool.ok());
  ASSERT_TRUE(GenerateFleet(**other_pool, SmallFleet(), [](const std::string&) {}).ok());
  auto second = (*(*other_pool)->Acquire())->Exec(fingerprint);
  ASSERT_TRUE(second.ok());
  EXPECT_EQ(first->String(0, 0), second->String(0, 0));

  FleetGeneratorOptions reseeded = SmallFleet();
  reseeded.seed = 12;
  reseeded.serial_prefix = "G11";  // same serials, other lives
  auto third_db = insdiag::testing::ScratchDatabase::Create();
  ASSERT_TRUE(third_db.ok());
  auto third_pool = ConnectionPool::Create({.database_url = (*third_db)->url(), .max_connections = 2});
  ASSERT_TRUE(third_pool.ok());
  ASSERT_TRUE(GenerateFleet(**third_pool, reseeded, [](const std::string&) {}).ok());
  auto third = (*(*third_pool)->Acquire())->Exec(fingerprint);
  ASSERT_TRUE(third.ok());
  EXPECT_NE(first->String(0, 0), third->String(0, 0));
  other_pool->reset();
  third_pool->reset();
}

TEST_F(FleetGeneratorTest, TakenSerialsAreRefusedAndNothingIsWritten) {
  Generate(SmallFleet());
  auto lease = pool().Acquire();
  ASSERT_TRUE(lease.ok());
  const std::int64_t analyses = Count(**lease, "SELECT count(*) FROM analyses");
  auto again = GenerateFleet(pool(), SmallFleet(), [](const std::string&) {});
  ASSERT_FALSE(again.ok());
  EXPECT_EQ(again.status().code(), absl::StatusCode::kAlreadyExists) << again.status();
  EXPECT_THAT(std::string(again.status().message()), HasSubstr("serial prefix"));
  EXPECT_EQ(Count(**lease, "SELECT count(*) FROM analyses"), analyses);
  // Another prefix adds a second fleet beside the first.
  FleetGeneratorOptions second = SmallFleet();
  second.serial_prefix = "B";
  second.units = 5;
  const GeneratedFleet added = Generate(second);
  EXPECT_EQ(Count(**lease, "SELECT count(*) FROM analyses"), analyses + added.analyses);
}

TEST_F(FleetGeneratorTest, GeneratedHistoryReadsBackThroughTheStoresAndEveryStatisticAnswers) {
  const GeneratedFleet fleet = Generate(SmallFleet());
  // GetAnalysis: a report rebuilt from the rows, saying so.
  AnalysisStore analyses(pool());
  AnalysisQuery query;
  query.page_size = 5;
  query.include_reports = true;
  auto page = analyses.List(query);
  ASSERT_TRUE(page.ok()) << page.status();
  ASSERT_FALSE(page->analyses.empty());
  const std::string id = api::IdOrSelf(page->analyses.front().name, api::kAnalyses);
  auto stored = analyses.Get(id, true);
  ASSERT_TRUE(stored.ok()) << stored.status();
  const v1::Analysis analysis = server::ToProto(*stored);
  EXPECT_EQ(analysis.state(), v1::Analysis::SUCCEEDED);
  EXPECT_EQ(analysis.report().identified_size(), 18);
  EXPECT_NE(analysis.report().verdict(), v1::AnalysisReport::VERDICT_UNSPECIFIED);
  EXPECT_GT(analysis.report().nis_mean(), 0.0);
  ASSERT_FALSE(analysis.report().notes().empty());
  EXPECT_THAT(analysis.report().notes(0), HasSubstr("rebuilt"));
  EXPECT_EQ(server::ToProto(page->analyses.front()).report().identified_size(), 18);

  // A new diagnosis of a generated analysis works like any other.
  DiagnosisStore diagnoses(pool(), DecodeReportFindings);
  auto diagnosis = testing::DiagnoseStored(diagnoses, analysis.name());
  ASSERT_TRUE(diagnosis.ok()) << diagnosis.status();
  EXPECT_FALSE(diagnosis->candidates().empty());

  FleetStore stats(pool());
  auto statistics = stats.GetFleetStatistics({});
  ASSERT_TRUE(statistics.ok()) << statistics.status();
  EXPECT_EQ(statistics->unit_count, fleet.units);
  EXPECT_EQ(statistics->analysis_count, fleet.analyses);
  EXPECT_EQ(statistics->failure_count, fleet.confirmed_failures);
  EXPECT_EQ(statistics->no_fault_found_count, fleet.no_fault_found);
  auto counts = stats.ListFailureCounts({});
  ASSERT_TRUE(counts.ok()) << counts.status();
  EXPECT_EQ(counts->total, fleet.confirmed_failures);
  auto pareto = stats.GetFailurePareto({});
  ASSERT_TRUE(pareto.ok());
  EXPECT_EQ(pareto->total_failures, fleet.confirmed_failures);
  ParameterTrendQuery trend;
  trend.unit_type = "unitTypes/INS-2000";
  trend.parameter = "gyro_bias_gm.x.sigma";
  auto buckets = stats.GetParameterTrend(trend);
  ASSERT_TRUE(buckets.ok()) << buckets.status();
  std::int64_t bucketed = 0;
  for (const TrendBucket& b : buckets->buckets) bucketed += b.count;
  EXPECT_EQ(bucketed, fleet.analyses);
  ParameterPointQuery points;
  points.unit_type = "unitTypes/INS-2000";
  points.parameter = "gyro_arw.z";
  auto listed = stats.ListParameterTrends(points);
  ASSERT_TRUE(listed.ok()) << listed.status();
  EXPECT_EQ(listed->points.size(), 50u);
  auto ranked = stats.RankUnits({});
  ASSERT_TRUE(ranked.ok()) << ranked.status();
  EXPECT_EQ(ranked->units.size(), 50u);
}

TEST_F(FleetGeneratorTest, RefusesBadOptions) {
  FleetGeneratorOptions options = SmallFleet();
  options.units = -1;
  EXPECT_EQ(GenerateFleet(pool(), options, [](const std::string&) {}).status().code(),
            absl::StatusCode::kInvalidArgument);
  options = SmallFleet();
  options.analyses = 10;  // fewer than the acceptance tests
  EXPECT_EQ(GenerateFleet(pool(), options, [](const std::string&) {}).status().code(),
            absl::StatusCode::kInvalidArgument);
  options = SmallFleet();
  options.unit_type = "INS-9999";
  EXPECT_EQ(GenerateFleet(pool(), options, [](const std::string&) {}).status().code(), absl::StatusCode::kNotFound);
}

}  // namespace
}  // namespace insdiag::kb
