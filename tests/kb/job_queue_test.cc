// Analyses as jobs on a real PostgreSQL: concurrent claiming, leases,
// reaping of jobs whose worker died, retries.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <mutex>
#include <set>
#include <thread>

#include "analysis_codec.h"
#include "insdiag/api/resource_names.h"
#include "insdiag/kb/analysis_store.h"
#include "insdiag/kb/run_store.h"
#include "support/database_fixture.h"
#include "support/synthetic_run.h"

namespace insdiag::kb {
namespace {

using namespace std::chrono_literals;

class JobQueueTest : public insdiag::testing::DatabaseTest {
 protected:
  std::string StoreRun() {
    RunStore runs(pool());
    engine::BenchRun run = insdiag::testing::SyntheticStaticRun(50, 10.0, 7);
    run.metadata.unit_type = "INS-2000";
    auto stored = runs.Create(run, {.sha256 = "x", .request_id = "", .request_fingerprint = ""});
    EXPECT_TRUE(stored.ok()) << stored.status();
    return stored.ok() ? stored->id : "";
  }
  std::int64_t Scalar(const std::string& sql) {
    auto db = pool().Acquire();
    auto rows = (*db)->Exec(sql);
    EXPECT_TRUE(rows.ok()) << rows.status();
    return rows.ok() ? *rows->Int(0, 0) : -1;
  }
};

TEST_F(JobQueueTest, FourConcurrentWorkersRunTwoHundredJobsEachExactlyOnce) {
  const std::string run = StoreRun();
  AnalysisStore store(pool());
  std::set<std::string> created;
  for (int i = 0; i < 200; ++i) {
    auto a = store.Create(run, "", "");
    ASSERT_TRUE(a.ok()) << a.status();
    created.insert(api::IdOrSelf(a->name, api::kAnalyses));
  }
  auto workers_pool = ConnectionPool::Create({.database_url = database_url(), .max_connections = 8});
  ASSERT_TRUE(workers_pool.ok());
  std::mutex mutex;
  std::multiset<std::string> ran;
  std::vector<int> per_worker(4, 0);
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::thread> workers;
  for (int w = 0; w < 4; ++w) {
    workers.emplace_back([&, w] {
      AnalysisStore mine(**workers_pool);
      const std::string owner = "worker-" + std::to_string(w);
      for (;;) {
        auto job = mine.Claim(owner, 30s);
        ASSERT_TRUE(job.ok()) << job.status();
        if (!job->has_value()) return;
        v1::AnalysisReport report;
        report.set_verdict(v1::AnalysisReport::GOOD);
        ASSERT_TRUE(mine.Complete((*job)->analysis_id, owner, server::EncodedReport(report), server::ReportRowsOf(report),
                                  nullptr)
                        .ok());
        std::lock_guard lock(mutex);
        ran.insert((*job)->analysis_id);
        ++per_worker[static_cast<std::size_t>(w)];
      }
    });
  }
  for (auto& t : workers) t.join();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("200 jobs claimed and completed by 4 workers in %.3f s (%.0f jobs/s); per worker %d %d %d %d\n", seconds,
              200 / seconds, per_worker[0], per_worker[1], per_worker[2], per_worker[3]);
  EXPECT_EQ(ran.size(), 200u) << "a job ran twice or was lost";
  EXPECT_EQ(std::set<std::string>(ran.begin(), ran.end()), created);
  EXPECT_EQ(Scalar("SELECT count(*) FROM analyses WHERE state = 'SUCCEEDED' AND attempts = 1"), 200);
}

TEST_F(JobQueueTest, AJobWhoseWorkerStoppedIsTakenUpAgainAndFailsAfterItsLastAttempt) {
  const std::string run = StoreRun();
  AnalysisStore store(pool());
  auto a = store.Create(run, "", "", /*max_attempts=*/2);
  ASSERT_TRUE(a.ok());
  auto first = store.Claim("dead-worker", 1ms);
  ASSERT_TRUE(first.ok() && first->has_value());
  std::this_thread::sleep_for(20ms);
  // Its lease expired: another worker cannot claim it before a reaper puts it back.
  EXPECT_FALSE(store.Claim("other", 30s)->has_value());
  auto reaped = store.Reap();
  ASSERT_TRUE(reaped.ok());
  EXPECT_EQ(reaped->requeued, 1);
  auto second = store.Claim("live-worker", 1ms);
  ASSERT_TRUE(second.ok() && second->has_value());
  EXPECT_EQ((*second)->attempt, 2);
  // The first worker, back from the dead, cannot overwrite the job.
  EXPECT_EQ(store.Complete((*first)->analysis_id, "dead-worker", "", ReportRows(), nullptr).code(),
            absl::StatusCode::kFailedPrecondition);
  std::this_thread::sleep_for(20ms);
  reaped = store.Reap();
  EXPECT_EQ(reaped->failed, 1);
  auto failed = store.Get((*first)->analysis_id);
  ASSERT_TRUE(failed.ok());
  EXPECT_EQ(failed->state, AnalysisState::kFailed);
  EXPECT_THAT(failed->error->message, ::testing::HasSubstr("stopped 2 times"));
}

TEST_F(JobQueueTest, CancelEndsQueuedJobsAtOnceAndRunningOnesThroughTheirWorker) {
  const std::string run = StoreRun();
  AnalysisStore store(pool());
  auto queued = store.Create(run, "", "");
  auto running = store.Create(run, "", "");
  auto claimed = store.Claim("w", 30s);  // the older one
  ASSERT_TRUE(claimed.ok() && claimed->has_value());
  EXPECT_EQ((*claimed)->analysis_id, api::IdOrSelf(queued->name, api::kAnalyses));
  auto cancelled = store.Cancel(api::IdOrSelf(running->name, api::kAnalyses));
  EXPECT_EQ(cancelled->state, AnalysisState::kCancelled);
  auto requested = store.Cancel((*claimed)->analysis_id);
  EXPECT_EQ(requested->state, AnalysisState::kRunning);
  auto beat = store.Heartbeat((*claimed)->analysis_id, "w", 30s);
  EXPECT_TRUE(beat->owned);
  EXPECT_TRUE(beat->cancel_requested);
  ASSERT_TRUE(store.MarkCancelled((*claimed)->analysis_id, "w").ok());
  EXPECT_EQ(store.Get((*claimed)->analysis_id)->state, AnalysisState::kCancelled);
}

TEST_F(JobQueueTest, RequestIdMakesCreationIdempotent) {
  const std::string run = StoreRun();
  AnalysisStore store(pool());
  auto a = store.Create(run, "", "req-1");
  auto b = store.Create(run, "", "req-1");
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->name, b->name);
  v1::AnalysisSpec other;
  other.mutable_model()->add_effects("gyro_scale_factor");
  EXPECT_EQ(store.Create(run, server::EncodedSpec(other), "req-1").status().code(), absl::StatusCode::kAlreadyExists);
  EXPECT_EQ(store.Create("00000000-0000-0000-0000-000000000000", server::EncodedSpec(other), "").status().code(),
            absl::StatusCode::kNotFound);
}

// The queue lists newest first by (create time, id): page by page it is the
// whole list in its order, and a token the server did not issue is refused.
TEST_F(JobQueueTest, ListsAnalysesNewestFirstPageByPage) {
  const std::string run = StoreRun();
  AnalysisStore store(pool());
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(store.Create(run, "", "").ok());
  const auto names = [&](int page_size) {
    std::vector<std::string> out;
    AnalysisQuery query;
    query.page_size = page_size;
    query.run_id = run;
    for (int pages = 0; pages < 10; ++pages) {
      auto page = store.List(query);
      EXPECT_TRUE(page.ok()) << page.status();
      if (!page.ok()) break;
      for (const auto& a : page->analyses) out.push_back(a.name);
      if (page->next_page_token.empty()) break;
      query.page_token = page->next_page_token;
    }
    return out;
  };
  EXPECT_EQ(names(50).size(), 5u);
  EXPECT_EQ(names(2), names(50));
  AnalysisQuery forged;
  forged.page_token = "not a token";
  EXPECT_EQ(store.List(forged).status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace insdiag::kb
