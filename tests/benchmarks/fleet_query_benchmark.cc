// fleet_query_benchmark — times every FleetService query (the store calls the
// server's handlers delegate to: SQL and the life statistics' fits, not the
// mapping to insdiag.v1) against a knowledge base holding a generated fleet
// (scripts/fleet-benchmark.sh prepares one with insdiag-fleet: 10,000 units,
// 1,000,000 analyses).
//
//   fleet_query_benchmark --database-url URL [--repetitions N] [--budget-ms MS]
//
// Each query runs once to warm the caches, then N times; prints a Markdown
// table (min, median, p95, max in ms) and exits 1 when a query's p95 is over
// the budget (200 ms), 2 for bad usage.
#include <absl/strings/str_format.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

#include "insdiag/kb/connection_pool.h"
#include "insdiag/kb/fleet_store.h"

namespace {

using namespace insdiag;

struct Query {
  std::string name;
  std::function<absl::Status()> run;
};

template <typename T>
absl::Status StatusOf(const absl::StatusOr<T>& result) {
  return result.status();
}

int Usage() {
  std::cerr << "usage: fleet_query_benchmark --database-url URL [--repetitions N] [--budget-ms MS]\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::string url;
  int repetitions = 20;
  double budget_ms = 200;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (i + 1 >= argc) return Usage();
    if (arg == "--database-url") {
      url = argv[++i];
    } else if (arg == "--repetitions") {
      repetitions = std::atoi(argv[++i]);
    } else if (arg == "--budget-ms") {
      budget_ms = std::atof(argv[++i]);
    } else {
      return Usage();
    }
  }
  if (url.empty() || repetitions < 1) return Usage();
  auto pool = kb::ConnectionPool::Create({.database_url = url, .max_connections = 2});
  if (!pool.ok()) {
    std::cerr << pool.status() << "\n";
    return 1;
  }
  kb::FleetStore fleet(**pool);
  const std::string type = "unitTypes/INS-2000";

  // Page tokens and a unit and a batch to ask about, from the data.
  kb::ParameterPointQuery points;
  points.unit_type = type;
  points.parameter = "gyro_bias_gm.x.sigma";
  points.page.page_size = 100;
  std::string deep_token;
  for (int page = 0; page < 50; ++page) {
    auto listed = fleet.ListParameterTrends(points);
    if (!listed.ok() || listed->next_page_token.empty()) break;
    points.page.page_token = listed->next_page_token;
    deep_token = listed->next_page_token;
  }
  kb::UnitRankingQuery rank;
  rank.unit_type = type;
  auto first_rank = fleet.RankUnits(rank);
  if (!first_rank.ok() || first_rank->units.empty()) {
    std::cerr << "no ranked units: generate a fleet first (scripts/fleet-benchmark.sh)\n";
    return 1;
  }
  const std::string rank_token = first_rank->next_page_token;
  const std::string unit = first_rank->units.front().unit;
  const std::string batch = first_rank->units.front().batch;

  std::vector<Query> queries;
  queries.push_back({"GetFleetStatistics (whole fleet)", [&] { return StatusOf(fleet.GetFleetStatistics({})); }});
  queries.push_back({"GetFleetStatistics (unit type)", [&] {
                       kb::FleetStatisticsQuery r;
                       r.unit_type = type;
                       return StatusOf(fleet.GetFleetStatistics(r));
                     }});
  queries.push_back({"ListFailureCounts (month × mode × type × batch)", [&] {
                       kb::FailureCountQuery r;
                       r.unit_type = type;
                       return StatusOf(fleet.ListFailureCounts(r));
                     }});
  queries.push_back({"ListFailureCounts (year, one mode)", [&] {
                       kb::FailureCountQuery r;
                       r.period = "year";
                       r.failure_mode = "failureModes/dtg-bearing-wear.x";
                       return StatusOf(fleet.ListFailureCounts(r));
                     }});
  queries.push_back({"GetFailurePareto", [&] {
                       kb::FailureParetoQuery r;
                       r.unit_type = type;
                       return StatusOf(fleet.GetFailurePareto(r));
                     }});
  queries.push_back({"GetWeibullFit (gyro.x, any mode)", [&] {
                       kb::WeibullFitQuery r;
                       r.unit_type = type;
                       r.module_role = "gyro.x";
                       return StatusOf(fleet.GetWeibullFit(r));
                     }});
  queries.push_back({"GetWeibullFit (gyro.x, dtg-bearing-wear.x)", [&] {
                       kb::WeibullFitQuery r;
                       r.module_role = "gyro.x";
                       r.failure_mode = "failureModes/dtg-bearing-wear.x";
                       return StatusOf(fleet.GetWeibullFit(r));
                     }});
  queries.push_back({"GetWeibullFit (power_supply, any mode)", [&] {
                       kb::WeibullFitQuery r;
                       r.module_role = "power_supply";
                       return StatusOf(fleet.GetWeibullFit(r));
                     }});
  queries.push_back({"GetParameterTrend (all batches)", [&] {
                       kb::ParameterTrendQuery r;
                       r.unit_type = type;
                       r.parameter = "gyro_bias_gm.x.sigma";
                       return StatusOf(fleet.GetParameterTrend(r));
                     }});
  queries.push_back({"GetParameterTrend (one batch)", [&] {
                       kb::ParameterTrendQuery r;
                       r.unit_type = type;
                       r.parameter = "acc_vrw.z";
                       r.batch = batch;
                       return StatusOf(fleet.GetParameterTrend(r));
                     }});
  queries.push_back({"ListParameterTrends (first page)", [&] {
                       kb::ParameterPointQuery r;
                       r.unit_type = type;
                       r.parameter = "gyro_arw.y";
                       return StatusOf(fleet.ListParameterTrends(r));
                     }});
  queries.push_back({"ListParameterTrends (page 51 of 100 points)", [&] {
                       kb::ParameterPointQuery r;
                       r.unit_type = type;
                       r.parameter = "gyro_bias_gm.x.sigma";
                       r.page.page_size = 100;
                       r.page.page_token = deep_token;
                       return StatusOf(fleet.ListParameterTrends(r));
                     }});
  queries.push_back({"ListParameterTrends (one unit)", [&] {
                       kb::ParameterPointQuery r;
                       r.unit_type = type;
                       r.parameter = "gyro_bias_gm.z.tau";
                       r.unit = unit;
                       r.page.page_size = 1000;
                       return StatusOf(fleet.ListParameterTrends(r));
                     }});
  queries.push_back({"RankUnits (first page)", [&] { return StatusOf(fleet.RankUnits(rank)); }});
  queries.push_back({"RankUnits (second page)", [&] {
                       kb::UnitRankingQuery r = rank;
                       r.page.page_token = rank_token;
                       return StatusOf(fleet.RankUnits(r));
                     }});

  std::cout << "| query | min [ms] | median [ms] | p95 [ms] | max [ms] |\n|---|---|---|---|---|\n";
  bool within = true;
  for (const auto& q : queries) {
    if (auto warm = q.run(); !warm.ok()) {
      std::cerr << q.name << ": " << warm << "\n";
      return 1;
    }
    std::vector<double> ms;
    for (int i = 0; i < repetitions; ++i) {
      const auto start = std::chrono::steady_clock::now();
      if (auto s = q.run(); !s.ok()) {
        std::cerr << q.name << ": " << s << "\n";
        return 1;
      }
      ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    }
    std::sort(ms.begin(), ms.end());
    const double p95 = ms[std::min(ms.size() - 1, static_cast<std::size_t>(0.95 * static_cast<double>(ms.size())))];
    std::cout << absl::StrFormat("| %s | %.1f | %.1f | %.1f | %.1f |\n", q.name, ms.front(), ms[ms.size() / 2], p95,
                                 ms.back());
    within = within && p95 <= budget_ms;
  }
  if (!within) std::cerr << "fleet_query_benchmark: a query's p95 is over " << budget_ms << " ms\n";
  return within ? 0 : 1;
}
