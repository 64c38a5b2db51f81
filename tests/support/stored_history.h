// A unit's history written straight through the stores, for the db tests:
// a run tested on a given day and a SUCCEEDED analysis of it with a given
// report, as a worker would have completed it.
#pragma once

#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "analysis_codec.h"  // server/src: the report as the server stores it
#include "insdiag/kb/analysis_store.h"
#include "insdiag/kb/run_store.h"
#include "support/synthetic_run.h"

namespace insdiag::testing {

// A SUCCEEDED analysis of runs/{run_id} with `report`; its name.
inline std::string AnalyseStoredRun(kb::ConnectionPool& pool, const std::string& run_id,
                                    const v1::AnalysisReport& report) {
  using namespace std::chrono_literals;
  kb::AnalysisStore analyses(pool);
  auto a = analyses.Create(run_id, server::EncodedSpec(v1::AnalysisSpec()), "");
  EXPECT_TRUE(a.ok()) << a.status();
  auto job = analyses.Claim("test worker", 30s);
  EXPECT_TRUE(job.ok() && job->has_value());
  EXPECT_TRUE(analyses
                  .Complete((*job)->analysis_id, "test worker", server::EncodedReport(report),
                            server::ReportRowsOf(report), nullptr)
                  .ok());
  return a.ok() ? a->name : "";
}

// A run of INS-2000 `serial` tested `days` after 2026-01-05 08:00 UTC, and
// a SUCCEEDED analysis of it with `report`; the analysis's name (and the
// run's id in `run_id`).
inline std::string StoreAnalysedRun(kb::ConnectionPool& pool, const std::string& serial, double days,
                                    const v1::AnalysisReport& report, std::string* run_id = nullptr) {
  kb::RunStore runs(pool);
  engine::BenchRun run = SyntheticStaticRun(20, 10.0, 3);
  run.metadata.unit_serial = serial;
  run.metadata.unit_type = "INS-2000";
  auto stored = runs.Create(run, {.sha256 = "x", .request_id = "", .request_fingerprint = ""});
  EXPECT_TRUE(stored.ok()) << stored.status();
  if (!stored.ok()) return "";
  // The bench test's date (an upload's is its upload time).
  auto db = pool.Acquire();
  EXPECT_TRUE(db.ok());
  EXPECT_TRUE((*db)->Exec("UPDATE runs SET test_time = timestamptz '2026-01-05 08:00+00' + $2::double precision * "
                          "interval '1 day' WHERE run_id = $1::uuid",
                          {kb::Param::Text(stored->id), kb::Param::Double(days)})
                  .ok());
  if (run_id != nullptr) *run_id = stored->id;
  return AnalyseStoredRun(pool, stored->id, report);
}

}  // namespace insdiag::testing
