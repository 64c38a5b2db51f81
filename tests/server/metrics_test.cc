// GET /metrics through a real server and a real HTTP client: the Prometheus
// text format, counters that move with the traffic, histograms whose
// buckets add up, the queue gauges moving with a queued job, the pool
// gauges, and the token check.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "insdiag/client/unary.h"
#include "insdiag/v1/analyses.grpc.pb.h"
#include "server_fixture.h"
#include "support/synthetic_run.h"

namespace insdiag::testing {
namespace {

using ::testing::HasSubstr;

// One scrape: every sample by its full name with labels, as written.
struct Scrape {
  std::map<std::string, double> samples;
  std::map<std::string, std::string> types;  // family → counter, gauge, histogram
};

// Parses the text exposition format 0.0.4; a line it cannot read fails the test.
Scrape Parse(const std::string& text) {
  static const std::regex kSample(R"(^([a-zA-Z_:][a-zA-Z0-9_:]*(\{[^}]*\})?) ([-+0-9.eE]+|NaN|[+-]Inf)$)");
  static const std::regex kType(R"(^# TYPE ([a-zA-Z_:][a-zA-Z0-9_:]*) (counter|gauge|histogram|summary|untyped)$)");
  static const std::regex kHelp(R"(^# HELP [a-zA-Z_:][a-zA-Z0-9_:]* .+$)");
  Scrape scrape;
  std::istringstream lines(text);
  std::string line;
  int number = 0;
  while (std::getline(lines, line)) {
    ++number;
    std::smatch m;
    if (std::regex_match(line, m, kType)) {
      scrape.types[m[1]] = m[2];
    } else if (std::regex_match(line, m, kSample)) {
      scrape.samples[m[1]] = std::stod(m[3]);
    } else {
      EXPECT_TRUE(std::regex_match(line, kHelp)) << "line " << number << " is not Prometheus text: " << line;
    }
  }
  return scrape;
}

class MetricsTest : public ServerTest {
 protected:
  Scrape Get(httplib::Client& client) {
    auto response = client.Get("/metrics");
    EXPECT_TRUE(response);
    if (!response) return {};
    EXPECT_EQ(response->status, 200) << response->body;
    EXPECT_THAT(response->get_header_value("Content-Type"), HasSubstr("text/plain; version=0.0.4"));
    return Parse(response->body);
  }

  double Sample(const Scrape& s, const std::string& name) {
    const auto it = s.samples.find(name);
    return it == s.samples.end() ? 0.0 : it->second;
  }

  // Scrapes until `sample` reaches `at_least` (a minute at most).
  Scrape Until(httplib::Client& client, const std::string& sample, double at_least) {
    Scrape s = Get(client);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (Sample(s, sample) < at_least && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      s = Get(client);
    }
    return s;
  }

  // `asked` created, then read until it ends (three minutes at most).
  v1::Analysis Ended(const v1::Analysis& asked) {
    auto analyses = v1::AnalysisService::NewStub(channel());
    v1::CreateAnalysisRequest create;
    *create.mutable_analysis() = asked;
    v1::Analysis analysis;
    {
      grpc::ClientContext context;
      EXPECT_TRUE(analyses->CreateAnalysis(&context, create, &analysis).ok());
    }
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(3);
    while (analysis.state() == v1::Analysis::QUEUED || analysis.state() == v1::Analysis::RUNNING) {
      if (std::chrono::steady_clock::now() > deadline) {
        ADD_FAILURE() << "the analysis did not end";
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      grpc::ClientContext context;
      v1::GetAnalysisRequest get;
      get.set_name(analysis.name());
      EXPECT_TRUE(analyses->GetAnalysis(&context, get, &analysis).ok());
    }
    return analysis;
  }
};

TEST_F(MetricsTest, AnswersOnlyAValidTokenAndAnyRoleReadsIt) {
  httplib::Client anonymous("127.0.0.1", server_->http_port());
  auto refused = anonymous.Get("/metrics");
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, 401);
  httplib::Client forged("127.0.0.1", server_->http_port());
  forged.set_bearer_token_auth("not-a-token");
  auto forged_answer = forged.Get("/metrics");
  ASSERT_TRUE(forged_answer);
  EXPECT_EQ(forged_answer->status, 401);
  httplib::Client viewer("127.0.0.1", server_->http_port());
  viewer.set_bearer_token_auth(MakeToken(pool(), v1::VIEWER, "metrics scraper").c_str());
  const Scrape s = Get(viewer);
  EXPECT_EQ(s.types.at("insdiag_grpc_calls_total"), "counter");
  EXPECT_EQ(s.types.at("insdiag_grpc_calls_duration_seconds"), "histogram");
  EXPECT_EQ(s.types.at("insdiag_jobs_queued"), "gauge");
  EXPECT_EQ(Sample(s, "insdiag_database_up"), 1.0);
  EXPECT_GE(Sample(s, "insdiag_database_connections{state=\"max\"}"), 1.0);
}

TEST_F(MetricsTest, CallsAndRequestsMoveTheCountersAndTheHistogramsAddUp) {
  httplib::Client viewer("127.0.0.1", server_->http_port());
  viewer.set_bearer_token_auth(MakeToken(pool(), v1::VIEWER).c_str());
  const std::string calls = R"(insdiag_grpc_calls_total{method="/insdiag.v1.RunService/ListRuns",code="OK"})";
  const std::string not_found = R"(insdiag_grpc_calls_total{method="/insdiag.v1.RunService/GetRun",code="NOT_FOUND"})";
  const std::string http_ok = R"(insdiag_http_requests_total{method="GET",status="200"})";
  const Scrape before = Get(viewer);

  constexpr int kCalls = 5;
  for (int i = 0; i < kCalls; ++i) {
    grpc::ClientContext context;
    v1::ListRunsRequest request;
    v1::ListRunsResponse response;
    ASSERT_TRUE(runs().ListRuns(&context, request, &response).ok());
  }
  {
    grpc::ClientContext context;
    v1::GetRunRequest request;
    request.set_name("runs/00000000-0000-0000-0000-000000000000");
    v1::Run response;
    EXPECT_EQ(runs().GetRun(&context, request, &response).error_code(), grpc::StatusCode::NOT_FOUND);
  }
  for (int i = 0; i < kCalls; ++i) ASSERT_TRUE(http().Get("/v1/runs"));  // REST: an HTTP request and a call

  // httplib counts a request in its logger, after the answer is written, so a
  // client can hold an answer its server has not counted yet. Scrape until
  // every earlier request is counted: the first scrape, the REST requests and
  // each repeated scrape but the latest, whose own request it cannot hold.
  Scrape after = Get(viewer);
  int repeated_scrapes = 0;
  const auto counted_ok = [&] { return Sample(after, http_ok) - Sample(before, http_ok); };
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (counted_ok() < kCalls + 1 + repeated_scrapes &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    after = Get(viewer);
    ++repeated_scrapes;
  }
  // The REST requests reach ListRuns through the gateway's in-process channel.
  EXPECT_EQ(Sample(after, calls) - Sample(before, calls), 2 * kCalls);
  EXPECT_EQ(Sample(after, not_found) - Sample(before, not_found), 1);
  EXPECT_GE(counted_ok(), kCalls + 1 + repeated_scrapes);

  // Every histogram: cumulative buckets, +Inf equal to the count and to the counter.
  const std::string family = "insdiag_grpc_calls_duration_seconds";
  const std::string labels = R"(method="/insdiag.v1.RunService/ListRuns",code="OK")";
  // Bucket order by bound, not by name: read them by their bounds.
  std::vector<std::pair<double, double>> by_bound;
  for (const auto& [name, value] : after.samples) {
    const std::string prefix = family + "_bucket{" + labels + ",le=\"";
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string bound = name.substr(prefix.size(), name.size() - prefix.size() - 2);
    by_bound.emplace_back(bound == "+Inf" ? INFINITY : std::stod(bound), value);
  }
  std::sort(by_bound.begin(), by_bound.end());
  EXPECT_GE(by_bound.size(), 10u);
  double previous = 0.0;
  for (const auto& [bound, count] : by_bound) {
    EXPECT_GE(count, previous) << "bucket le=" << bound << " below the one before";
    previous = count;
  }
  ASSERT_FALSE(by_bound.empty());
  EXPECT_EQ(by_bound.back().second, Sample(after, family + "_count{" + labels + "}"));
  EXPECT_EQ(by_bound.back().second, Sample(after, calls));
  EXPECT_GT(Sample(after, family + "_sum{" + labels + "}"), 0.0);
}

TEST_F(MetricsTest, AnAnalysisJobCountsByItsOutcomeWithItsDuration) {
  httplib::Client viewer("127.0.0.1", server_->http_port());
  viewer.set_bearer_token_auth(MakeToken(pool(), v1::VIEWER).c_str());
  auto run = client::UploadRun(runs(), SyntheticStaticRun(30000, 50.0, 5), client::UploadOptions{});
  ASSERT_TRUE(run.ok()) << run.status();
  v1::Analysis asked;
  asked.set_run(run->name());
  const v1::Analysis analysis = Ended(asked);
  ASSERT_EQ(analysis.state(), v1::Analysis::SUCCEEDED) << analysis.error().message();
  const std::string outcome = "succeeded";
  // The job's count is written after its state: wait for it.
  const Scrape s = Until(viewer, "insdiag_analyses_total{outcome=\"" + outcome + "\"}", 1.0);
  EXPECT_EQ(Sample(s, "insdiag_analyses_total{outcome=\"" + outcome + "\"}"), 1.0);
  EXPECT_EQ(Sample(s, "insdiag_analysis_duration_seconds_count{outcome=\"" + outcome + "\"}"), 1.0);
  EXPECT_GT(Sample(s, "insdiag_analysis_duration_seconds_sum{outcome=\"" + outcome + "\"}"), 0.0);
  EXPECT_EQ(Sample(s, "insdiag_jobs_queued"), 0.0);
  EXPECT_EQ(Sample(s, "insdiag_jobs_running"), 0.0);
}

// The page's Add on an analysis: the worker, with nothing queued, kept model
// A of that Add, and the Add runs on the run's preparation and that model A;
// and so on for an Add from that Add.
TEST_F(MetricsTest, ThePagesAddTakesTheRunsPreparationAndAModelAKeptWhileTheWorkerWasIdle) {
  httplib::Client viewer("127.0.0.1", server_->http_port());
  viewer.set_bearer_token_auth(MakeToken(pool(), v1::VIEWER).c_str());
  auto run = client::UploadRun(runs(), SyntheticStaticRun(6000, 50.0, 7), client::UploadOptions{});
  ASSERT_TRUE(run.ok()) << run.status();
  v1::Analysis asked;
  asked.set_run(run->name());
  const v1::Analysis a = Ended(asked);
  ASSERT_EQ(a.state(), v1::Analysis::SUCCEEDED) << a.error().message();
  const Scrape idle = Until(viewer, "insdiag_analysis_cache_made_total{part=\"model_a\"}", 1.0);
  EXPECT_EQ(Sample(idle, "insdiag_analysis_cache_made_total{part=\"model_a\"}"), 1.0);
  EXPECT_EQ(Sample(idle, "insdiag_analysis_cache_made_total{part=\"preparation\"}"), 1.0);
  EXPECT_GT(Sample(idle, "insdiag_analysis_cache_bytes"), 6000.0 * 80.0) << "the samples at least";

  asked.set_base_analysis(a.name());
  asked.mutable_model()->add_effects("gyro_scale_factor.z");
  const v1::Analysis b = Ended(asked);
  ASSERT_EQ(b.state(), v1::Analysis::SUCCEEDED) << b.error().message();
  ASSERT_TRUE(b.report().has_comparison());
  const Scrape after = Get(viewer);
  EXPECT_EQ(Sample(after, "insdiag_analysis_cache_made_total{part=\"preparation\"}"), 1.0);
  EXPECT_EQ(Sample(after, "insdiag_analysis_cache_reused_total{part=\"model_a\"}"), 1.0);
  EXPECT_EQ(Sample(after, "insdiag_analysis_cache_reused_total{part=\"preparation\"}"), 2.0)
      << "model A kept while idle, then the Add";
  EXPECT_EQ(after.types.at("insdiag_analysis_cache_reused_total"), "counter");

  // An Add from that Add: its baseline holds the added effect, so the kept
  // screened run is condensed again under it (while the worker is idle),
  // never read again.
  EXPECT_EQ(Sample(Until(viewer, "insdiag_analysis_cache_made_total{part=\"model_a\"}", 2.0),
                   "insdiag_analysis_cache_made_total{part=\"model_a\"}"),
            2.0);
  asked.set_base_analysis(b.name());
  asked.mutable_model()->set_effects(0, "gyro_scale_factor.x");
  const v1::Analysis c = Ended(asked);
  ASSERT_EQ(c.state(), v1::Analysis::SUCCEEDED) << c.error().message();
  const Scrape last = Get(viewer);
  EXPECT_EQ(Sample(last, "insdiag_analysis_cache_made_total{part=\"preparation\"}"), 1.0) << "read once";
  // Once for the Add from B; the idle worker may since have condensed it for
  // an Add from C as well.
  EXPECT_GE(Sample(last, "insdiag_analysis_cache_reused_total{part=\"screening\"}"), 1.0);
  EXPECT_EQ(Sample(last, "insdiag_analysis_cache_reused_total{part=\"model_a\"}"), 2.0);
}

// With no worker to take it, a queued analysis shows in the queue's gauges:
// one queued, its age growing from scrape to scrape; cancelled, none.
class QueueMetricsTest : public MetricsTest {
 protected:
  void Configure(server::InsdiagServer::Options& options) override { options.workers.workers = 0; }
};

TEST_F(QueueMetricsTest, AQueuedAnalysisMovesTheQueueDepthAndAgeGauges) {
  httplib::Client viewer("127.0.0.1", server_->http_port());
  viewer.set_bearer_token_auth(MakeToken(pool(), v1::VIEWER).c_str());
  const Scrape idle = Get(viewer);
  EXPECT_EQ(Sample(idle, "insdiag_jobs_queued"), 0.0);
  EXPECT_EQ(Sample(idle, "insdiag_jobs_oldest_queued_age_seconds"), 0.0);

  auto run = client::UploadRun(runs(), SyntheticStaticRun(500, 50.0, 6), client::UploadOptions{});
  ASSERT_TRUE(run.ok()) << run.status();
  auto analyses = v1::AnalysisService::NewStub(channel());
  v1::CreateAnalysisRequest create;
  create.mutable_analysis()->set_run(run->name());
  auto queued = client::CallUnary<v1::Analysis>([&](grpc::ClientContext* c, v1::Analysis* r) {
    return analyses->CreateAnalysis(c, create, r);
  });
  ASSERT_TRUE(queued.ok()) << queued.status();
  ASSERT_EQ(queued->state(), v1::Analysis::QUEUED);

  const Scrape first = Get(viewer);
  EXPECT_EQ(Sample(first, "insdiag_jobs_queued"), 1.0);
  EXPECT_EQ(Sample(first, "insdiag_jobs_running"), 0.0);
  const double first_age = Sample(first, "insdiag_jobs_oldest_queued_age_seconds");
  EXPECT_GE(first_age, 0.0);
  // The age grows while the job waits: scrape until it has (the database's
  // clock, in microseconds), with a deadline.
  Scrape later = Get(viewer);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (Sample(later, "insdiag_jobs_oldest_queued_age_seconds") <= first_age + 0.2 &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    later = Get(viewer);
  }
  EXPECT_GT(Sample(later, "insdiag_jobs_oldest_queued_age_seconds"), first_age + 0.2);
  EXPECT_EQ(Sample(later, "insdiag_jobs_queued"), 1.0);

  v1::CancelAnalysisRequest cancel;
  cancel.set_name(queued->name());
  auto cancelled = client::CallUnary<v1::Analysis>([&](grpc::ClientContext* c, v1::Analysis* r) {
    return analyses->CancelAnalysis(c, cancel, r);
  });
  ASSERT_TRUE(cancelled.ok()) << cancelled.status();
  EXPECT_EQ(cancelled->state(), v1::Analysis::CANCELLED);
  const Scrape after = Get(viewer);
  EXPECT_EQ(Sample(after, "insdiag_jobs_queued"), 0.0);
  EXPECT_EQ(Sample(after, "insdiag_jobs_oldest_queued_age_seconds"), 0.0);
}

}  // namespace
}  // namespace insdiag::testing
