#include "insdiag/kb/unit_history_store.h"

#include <absl/strings/str_cat.h>
#include <absl/time/time.h>

#include <algorithm>
#include <map>
#include <string_view>

#include "history_rows.h"
#include "insdiag/api/resource_names.h"
#include "insdiag/engine/status_macros.h"
#include "store_util.h"

namespace insdiag::kb {
namespace {

using internal::kRunTestTime;
using internal::Micros;

constexpr double kDefaultConfidence = 0.95;

// A verdict as the analyses table stores it ("GOOD"); none for any other text.
std::optional<engine::Verdict> VerdictOfName(std::string_view name) {
  for (engine::Verdict verdict : {engine::Verdict::kGood, engine::Verdict::kOperable, engine::Verdict::kFaulty}) {
    if (name == engine::VerdictName(verdict)) return verdict;
  }
  return std::nullopt;
}

// The page of runs, oldest first, each with its succeeded analyses.
absl::Status LoadRuns(Connection& db, const std::string& unit_id, const UnitHistoryQuery& query, UnitHistory& out) {
  const int size = internal::ClampPageSize(query.page_size);
  std::vector<Param> params = {Param::Text(unit_id), Param::Int(size + 1)};
  INSDIAG_ASSIGN_OR_RETURN(auto after,
                           internal::KeysetCondition(query.page_token, kRunTestTime, "r.run_id",
                                                     internal::KeysetOrder::kOldestFirst, params));
  INSDIAG_ASSIGN_OR_RETURN(
      auto runs,
      db.Exec(absl::StrCat("SELECT r.run_id::text, ", Micros(kRunTestTime), ", ", kRunTestTime,
                           "::text, r.duration_s FROM runs r WHERE r.unit_id = $1 AND ", after,
                           " ORDER BY ", kRunTestTime, ", r.run_id LIMIT $2"),
              params));
  const int shown = std::min(runs.rows(), size);
  std::vector<std::string> ids;
  std::map<std::string, std::size_t> index_of_id;  // in out.runs
  for (int r = 0; r < shown; ++r) {
    HistoryRun& run = out.runs.emplace_back();
    ids.push_back(runs.String(r, 0));
    run.run = api::ResourceName(api::kRuns, ids.back());
    run.test_time = absl::FromUnixMicros(internal::IntOr0(runs, r, 1));
    run.duration_s = internal::DoubleOr0(runs, r, 3);
    index_of_id[ids.back()] = out.runs.size() - 1;
  }
  if (runs.rows() > size) out.next_page_token = internal::EncodeToken(runs.String(shown - 1, 2), ids.back());
  if (ids.empty()) return absl::OkStatus();
  // `counted`: ordered as history_rows.cc picks the run's analysis.
  auto analyses = db.Exec(
      absl::StrCat("SELECT a.run_id::text, a.analysis_id::text, ", Micros("a.create_time"),
                   ", coalesce(a.verdict, ''), coalesce(a.unit_hours, 0), "
                   "(SELECT count(*) FROM identified_parameters p WHERE p.analysis_id = a.analysis_id), "
                   "row_number() OVER (PARTITION BY a.run_id ORDER BY a.end_time DESC NULLS LAST, "
                   "a.create_time DESC, a.analysis_id DESC) = 1 "
                   "FROM analyses a WHERE a.run_id = ANY($1::uuid[]) AND a.state = 'SUCCEEDED' "
                   "ORDER BY a.create_time, a.analysis_id"),
      {Param::TextArray(ids)});
  if (!analyses.ok()) return analyses.status();
  for (int r = 0; r < analyses->rows(); ++r) {
    HistoryAnalysis& a = out.runs[index_of_id.at(analyses->String(r, 0))].analyses.emplace_back();
    a.analysis = api::ResourceName(api::kAnalyses, analyses->String(r, 1));
    a.create_time = absl::FromUnixMicros(internal::IntOr0(*analyses, r, 2));
    a.verdict = VerdictOfName(analyses->String(r, 3));
    a.unit_hours = internal::DoubleOr0(*analyses, r, 4);
    a.identified_count = static_cast<int>(internal::IntOr0(*analyses, r, 5));
    a.counted = analyses->Bool(r, 6);
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<UnitHistory> UnitHistoryStore::Get(const UnitHistoryQuery& query) {
  auto serial = api::ResourceId(query.unit, api::kUnits, "unit");
  if (!serial.ok()) return serial.status();
  HistoryOptions options;
  options.confidence = query.confidence == 0.0 ? kDefaultConfidence : query.confidence;
  if (!options.Validate()) return absl::InvalidArgumentError("confidence: must lie strictly between 0 and 1");
  INSDIAG_ASSIGN_OR_RETURN(auto db, pool_.Acquire());
  INSDIAG_ASSIGN_OR_RETURN(auto unit,
                           db->Exec("SELECT u.unit_id, coalesce(u.unit_type, ''), "
                                    "(SELECT count(*) FROM runs r WHERE r.unit_id = u.unit_id), "
                                    "(SELECT count(DISTINCT a.run_id) FROM analyses a WHERE "
                                    "a.unit_id = u.unit_id AND a.state = 'SUCCEEDED') "
                                    "FROM units u WHERE u.serial = $1",
                                    {Param::Text(*serial)}));
  if (unit.rows() == 0) return absl::NotFoundError(absl::StrCat(query.unit, " does not exist"));
  UnitHistory out;
  out.unit = api::ResourceName(api::kUnits, *serial);
  if (!unit.String(0, 1).empty()) out.unit_type = api::ResourceName(api::kUnitTypes, unit.String(0, 1));
  out.run_count = static_cast<int>(internal::IntOr0(unit, 0, 2));
  out.analysed_run_count = static_cast<int>(internal::IntOr0(unit, 0, 3));
  out.confidence = options.confidence;
  INSDIAG_RETURN_IF_ERROR(LoadRuns(*db, unit.String(0, 0), query, out));
  internal::HistoryScope scope;
  scope.unit_id = unit.String(0, 0);
  scope.only_parameters = query.parameters;
  INSDIAG_ASSIGN_OR_RETURN(out.parameters, internal::LoadParameterHistories(*db, scope, options));
  if (out.analysed_run_count < 2) {
    out.notes.push_back("fewer than two runs with a succeeded analysis: no repeatability yet");
  } else if (out.analysed_run_count < 3) {
    out.notes.push_back("fewer than three runs with a succeeded analysis: no trend yet");
  }
  return out;
}

}  // namespace insdiag::kb
