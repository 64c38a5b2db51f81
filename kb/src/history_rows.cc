#include "history_rows.h"

#include <absl/strings/str_cat.h>
#include <absl/time/time.h>

#include "insdiag/api/resource_names.h"
#include "insdiag/engine/model/parameters.h"
#include "store_util.h"

namespace insdiag::kb::internal {

absl::StatusOr<std::vector<ParameterHistory>> LoadParameterHistories(Connection& db, const HistoryScope& scope,
                                                                     const HistoryOptions& options) {
  // One analysis per run: the cut-off analysis for its own run, else the
  // run's latest succeeded one (a model B or a discovery's last step
  // carries the fullest model).
  auto rows = db.Exec(
      absl::StrCat(
          "WITH cut AS (SELECT a.run_id, ", kRunTestTime, " AS tested FROM analyses a JOIN runs r USING (run_id) "
          "WHERE a.analysis_id = $2::uuid), "
          "counted AS (SELECT DISTINCT ON (a.run_id) a.run_id, a.analysis_id, ", kRunTestTime, " AS tested "
          "FROM analyses a JOIN runs r USING (run_id) WHERE a.unit_id = $1 AND a.state = 'SUCCEEDED' "
          "AND ($2::uuid IS NULL OR (", kRunTestTime, " <= (SELECT tested FROM cut) "
          "AND (a.run_id <> (SELECT run_id FROM cut) OR a.analysis_id = $2::uuid))) "
          "ORDER BY a.run_id, a.end_time DESC NULLS LAST, a.create_time DESC, a.analysis_id DESC) "
          "SELECT n.name, c.run_id::text, c.analysis_id::text, ", Micros("c.tested"),
          ", p.value, coalesce(p.std_error, 0) "
          "FROM counted c JOIN identified_parameters p USING (analysis_id) JOIN parameter_names n USING (parameter_id) "
          "WHERE ($3::text[] IS NULL OR n.name = ANY($3::text[])) ORDER BY n.name, c.tested, c.run_id"),
      {Param::Text(scope.unit_id), Param::TextOrNull(scope.until_analysis_id),
       scope.only_parameters.empty() ? Param::Null() : Param::TextArray(scope.only_parameters)});
  if (!rows.ok()) return rows.status();
  constexpr double kMicrosPerDay = 86400e6;
  std::vector<ParameterHistory> out;
  std::int64_t first_micros = 0;
  for (int r = 0; r < rows->rows(); ++r) {
    const std::string name = rows->String(r, 0);
    if (out.empty() || out.back().name != name) {
      ParameterHistory& p = out.emplace_back();
      p.name = name;
      p.unit = engine::ParameterUnit(name);
      p.turn_on_bias = IsTurnOnBias(name);
      first_micros = IntOr0(*rows, r, 3);
    }
    RunParameterPoint& point = out.back().points.emplace_back();
    point.run = api::ResourceName(api::kRuns, rows->String(r, 1));
    point.analysis = api::ResourceName(api::kAnalyses, rows->String(r, 2));
    const std::int64_t micros = IntOr0(*rows, r, 3);
    point.test_time = absl::FromUnixMicros(micros);
    point.days = static_cast<double>(micros - first_micros) / kMicrosPerDay;
    point.value = DoubleOr0(*rows, r, 4);
    point.std_error = DoubleOr0(*rows, r, 5);
  }
  for (auto& p : out) {
    std::vector<HistoryPoint> points;
    for (const auto& q : p.points) points.push_back({q.days, q.value, q.std_error});
    p.statistics = ParameterStatisticsOf(points, p.turn_on_bias, options);
  }
  return out;
}

}  // namespace insdiag::kb::internal
