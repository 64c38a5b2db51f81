// Analyses as jobs through the real API: an in-process server with one
// worker over a fresh database, real gRPC and HTTP clients; and two real
// insdiagd processes sharing a database, one killed mid-job.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <chrono>
#include <thread>

#include "analysis_codec.h"
#include "insdiag/api/resource_names.h"
#include "insdiag/api/unit_types.h"
#include "insdiag/engine/model/parameters.h"
#include "insdiag/engine/sim/simulator.h"
#include "insdiag/kb/analysis_store.h"
#include "insdiag/kb/run_store.h"
#include "insdiag/v1/knowledge.grpc.pb.h"
#include "server_fixture.h"
#include "support/poll.h"
#include "support/subprocess.h"

namespace insdiag::testing {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;

// A simulated INS-2000 on the table: its unit type's nominal model, with
// `params` overridden and `effects` hidden.
engine::BenchRun SimulatedRun(const std::string& serial, const std::string& profile_name, double rate_hz,
                              const std::vector<std::pair<std::string, double>>& params = {},
                              const std::string& effect = "") {
  auto unit_type = api::BuiltinUnitType("INS-2000");
  auto model = api::BaseModelOf(*unit_type);
  engine::sim::SimulationOptions options;
  options.datasheet = engine::sim::DatasheetOf(model->gyro, model->acc);  // the type's specification
  for (const auto& [name, value] : params) EXPECT_TRUE(engine::SetParameter(name, value, *model).ok());
  engine::sim::SimulatedUnit unit;
  unit.serial = serial;
  unit.type = "INS-2000";
  unit.gyro = model->gyro;
  unit.acc = model->acc;
  if (!effect.empty()) {
    auto effects = engine::sim::ParseTrueEffect(effect);
    EXPECT_TRUE(effects.ok()) << effects.status();
    unit.effects = *effects;
  }
  auto profile = engine::sim::BuiltinProfile(profile_name);
  options.sample_rate_hz = rate_hz;
  options.seed = 11;
  options.site = {.latitude_rad = 0.97, .longitude_rad = 0.67, .height_m = 125.0};
  auto simulated = engine::sim::Simulate(unit, *profile, options);
  EXPECT_TRUE(simulated.ok()) << simulated.status();
  return simulated->run;
}

const v1::NominalParameter* NominalOf(const std::string& name) {
  static const auto unit_type = api::BuiltinUnitType("INS-2000");
  for (const auto& p : unit_type->nominal()) {
    if (p.name() == name) return &p;
  }
  ADD_FAILURE() << name << " has no nominal value in INS-2000";
  return nullptr;
}
double Nominal(const std::string& name) { return NominalOf(name) ? NominalOf(name)->value() : 0.0; }
double Tolerance(const std::string& name) { return NominalOf(name) ? NominalOf(name)->tolerance() : 0.0; }

class AnalysesTest : public ServerTest {
 protected:
  void SetUp() override {
    ServerTest::SetUp();
    if (IsSkipped() || HasFatalFailure()) return;
    analyses_ = v1::AnalysisService::NewStub(channel());
    knowledge_ = v1::KnowledgeService::NewStub(channel());
  }

  std::string Upload(const engine::BenchRun& run) {
    auto stored = client::UploadRun(runs(), run, {});
    EXPECT_TRUE(stored.ok()) << stored.status();
    return stored.ok() ? stored->name() : "";
  }

  v1::Analysis Create(const std::string& run, const std::vector<std::string>& effects = {}, bool discover = false) {
    grpc::ClientContext context;
    v1::CreateAnalysisRequest request;
    request.mutable_analysis()->set_run(run);
    request.mutable_analysis()->set_discover(discover);
    for (const auto& e : effects) request.mutable_analysis()->mutable_model()->add_effects(e);
    v1::Analysis analysis;
    const grpc::Status status = analyses_->CreateAnalysis(&context, request, &analysis);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return analysis;
  }

  // Watches until the end; returns every message seen. The deadline leaves
  // room for an eight-hour run's analysis on a slow two-core machine (2–3 min
  // beside another test) inside the test's own time limit (CMakeLists.txt).
  std::vector<v1::Analysis> Watch(const std::string& name) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + 480s);
    v1::WatchAnalysisRequest request;
    request.set_name(name);
    auto reader = analyses_->WatchAnalysis(&context, request);
    std::vector<v1::Analysis> seen;
    v1::Analysis a;
    while (reader->Read(&a)) seen.push_back(a);
    const grpc::Status status = reader->Finish();
    EXPECT_TRUE(status.ok()) << status.error_message();
    return seen;
  }

  v1::Diagnosis Diagnose(const std::string& analysis) {
    grpc::ClientContext context;
    v1::CreateDiagnosisRequest request;
    request.set_analysis(analysis);
    v1::Diagnosis diagnosis;
    const grpc::Status status = knowledge_->CreateDiagnosis(&context, request, &diagnosis);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return diagnosis;
  }

  // Upload, analyse through the job, diagnose.
  // As `insdiag diagnose` does: the server walks the loop, so the evidence is
  // effects estimated in the model.
  v1::Diagnosis DiagnoseRun(const engine::BenchRun& run) {
    const v1::Analysis created = Create(Upload(run), {}, /*discover=*/true);
    EXPECT_TRUE(created.discover());
    const auto seen = Watch(created.name());
    EXPECT_FALSE(seen.empty());
    if (seen.empty()) return {};
    EXPECT_EQ(seen.back().state(), v1::Analysis::SUCCEEDED) << seen.back().error().message();
    return Diagnose(created.name());
  }

  std::unique_ptr<v1::AnalysisService::Stub> analyses_;
  std::unique_ptr<v1::KnowledgeService::Stub> knowledge_;
};

TEST_F(AnalysesTest, CreateReturnsAtOnceThenWatchStreamsProgressToTheReportAndSeries) {
  const std::string run = Upload(SimulatedRun("INS-E2E-1", "static", 10.0));
  // Create answers with the job queued, before any worker has run it.
  const v1::Analysis created = Create(run);
  EXPECT_EQ(created.state(), v1::Analysis::QUEUED);
  EXPECT_EQ(created.run(), run);
  EXPECT_THAT(created.name(), ::testing::StartsWith("analyses/"));

  const auto seen = Watch(created.name());
  ASSERT_FALSE(seen.empty());
  const v1::Analysis& last = seen.back();
  EXPECT_EQ(last.state(), v1::Analysis::SUCCEEDED) << last.error().message();
  EXPECT_EQ(last.report().channels_size(), 9);  // position, velocity, attitude
  EXPECT_EQ(last.attempts(), 1);
  EXPECT_EQ(last.unit(), "units/INS-E2E-1");

  grpc::ClientContext get_context;
  v1::GetAnalysisRequest get;
  get.set_name(created.name());
  v1::Analysis got;
  ASSERT_TRUE(analyses_->GetAnalysis(&get_context, get, &got).ok());
  EXPECT_EQ(got.report().verdict(), last.report().verdict());

  grpc::ClientContext series_context;
  v1::ReadResidualSeriesRequest series;
  series.set_name(created.name());
  series.add_channels("vel_n");
  auto reader = analyses_->ReadResidualSeries(&series_context, series);
  v1::ResidualSeriesChunk chunk;
  int points = 0;
  while (reader->Read(&chunk)) {
    for (const auto& p : chunk.points()) {
      EXPECT_EQ(p.channel(), "vel_n");
      EXPECT_NEAR(p.residual(), p.measured() - p.predicted(), 1e-9 + 1e-6 * std::abs(p.measured()));
      ++points;
    }
  }
  ASSERT_TRUE(reader->Finish().ok());
  EXPECT_GT(points, 1000);

  // REST: the same analysis, and the watch as newline-delimited JSON.
  auto rest = http().Get(("/v1/" + created.name()).c_str());
  ASSERT_TRUE(rest);
  EXPECT_EQ(rest->status, 200);
  EXPECT_THAT(rest->body, HasSubstr("\"state\":\"SUCCEEDED\""));
  auto watched = http().Get(("/v1/" + created.name() + ":watch").c_str());
  ASSERT_TRUE(watched);
  EXPECT_THAT(watched->body, HasSubstr("SUCCEEDED"));
  auto listed = http().Get(("/v1/analyses?run=" + run).c_str());
  ASSERT_TRUE(listed);
  EXPECT_THAT(listed->body, HasSubstr(created.name()));
}

TEST_F(AnalysesTest, BadRequestsAreRefusedNamingTheField) {
  grpc::ClientContext context;
  v1::CreateAnalysisRequest request;
  request.mutable_analysis()->set_run("nonsense");
  v1::Analysis analysis;
  const grpc::Status status = analyses_->CreateAnalysis(&context, request, &analysis);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("analysis.run"));
  auto rest = http().Post("/v1/analyses", R"({"run":"runs/00000000-0000-0000-0000-000000000000"})", "application/json");
  ASSERT_TRUE(rest);
  EXPECT_EQ(rest->status, 404);
  auto diagnosis = http().Post("/v1/diagnoses", R"({"analysis":"analyses/x"})", "application/json");
  ASSERT_TRUE(diagnosis);
  EXPECT_EQ(diagnosis->status, 400);
}

// ReadDisplaySeries (the page's plots): the stored series, decimated to a
// min/max envelope per column of the requested range, raw when the range is short.
TEST_F(AnalysesTest, DisplaySeriesIsTheStoredSeriesDecimatedToThePlotsWidth) {
  const v1::Analysis created = Create(Upload(SimulatedRun("INS-E2E-3", "static", 10.0)));
  const auto seen = Watch(created.name());
  ASSERT_FALSE(seen.empty());
  ASSERT_EQ(seen.back().state(), v1::Analysis::SUCCEEDED) << seen.back().error().message();

  std::vector<v1::ResidualPoint> raw;
  {
    grpc::ClientContext context;
    v1::ReadResidualSeriesRequest request;
    request.set_name(created.name());
    request.add_channels("vel_e");
    auto reader = analyses_->ReadResidualSeries(&context, request);
    v1::ResidualSeriesChunk chunk;
    while (reader->Read(&chunk)) raw.insert(raw.end(), chunk.points().begin(), chunk.points().end());
    ASSERT_TRUE(reader->Finish().ok());
  }
  ASSERT_GT(raw.size(), 1000u);

  const auto display = [&](double start_s, double end_s, int columns) {
    grpc::ClientContext context;
    v1::ReadDisplaySeriesRequest request;
    request.set_name(created.name());
    request.add_channels("vel_e");
    request.set_start_s(start_s);
    request.set_end_s(end_s);
    request.set_columns(columns);
    v1::DisplaySeries series;
    const grpc::Status status = analyses_->ReadDisplaySeries(&context, request, &series);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return series;
  };

  // The whole run in 100 columns: each column holds the extremes of its epochs.
  const v1::DisplaySeries whole = display(0, 0, 100);
  EXPECT_DOUBLE_EQ(whole.series_start_s(), raw.front().t());
  EXPECT_DOUBLE_EQ(whole.series_end_s(), raw.back().t());
  ASSERT_EQ(whole.channels_size(), 1);
  const v1::ChannelEnvelope& envelope = whole.channels(0);
  EXPECT_EQ(envelope.channel(), "vel_e");
  EXPECT_TRUE(envelope.decimated());
  EXPECT_EQ(envelope.epochs(), static_cast<std::int64_t>(raw.size()));
  ASSERT_LE(envelope.t_size(), 100);
  ASSERT_GE(envelope.t_size(), 90);
  double highest = -1e300;
  double widest = 0;
  for (const auto& p : raw) {
    highest = std::max(highest, p.residual());
    widest = std::max(widest, p.sigma3());
  }
  EXPECT_DOUBLE_EQ(*std::max_element(envelope.residual_max().begin(), envelope.residual_max().end()), highest);
  EXPECT_DOUBLE_EQ(*std::max_element(envelope.sigma3_max().begin(), envelope.sigma3_max().end()), widest);

  // Twenty seconds in 1,000 columns: the epochs themselves.
  const double from = raw[raw.size() / 2].t();
  const v1::DisplaySeries zoomed = display(from, from + 20, 1000);
  ASSERT_EQ(zoomed.channels_size(), 1);
  EXPECT_FALSE(zoomed.channels(0).decimated());
  std::vector<double> expected;
  for (const auto& p : raw) {
    if (p.t() >= from && p.t() <= from + 20) expected.push_back(p.residual());
  }
  ASSERT_FALSE(expected.empty());
  EXPECT_THAT(zoomed.channels(0).residual_min(), ::testing::ElementsAreArray(expected));

  // REST, the page's way; a backward range is refused.
  auto rest = http().Get(("/v1/" + created.name() + "/displaySeries?channels=vel_e&columns=50").c_str());
  ASSERT_TRUE(rest);
  EXPECT_EQ(rest->status, 200);
  EXPECT_THAT(rest->body, HasSubstr("\"decimated\":true"));
  auto backward = http().Get(("/v1/" + created.name() + "/displaySeries?startS=10&endS=5").c_str());
  ASSERT_TRUE(backward);
  EXPECT_EQ(backward->status, 400);
}

// The page's Add: an analysis that starts from an earlier one's identified
// model runs model A's and model B's passes only; model A is the earlier
// analysis's to the bit.
TEST_F(AnalysesTest, AnAddStartsFromTheEarlierAnalysisIdentifiedModel) {
  const std::string run = Upload(SimulatedRun("INS-E2E-ADD", "static", 10.0));
  const v1::Analysis a = Create(run);
  const auto a_seen = Watch(a.name());
  ASSERT_FALSE(a_seen.empty());
  ASSERT_EQ(a_seen.back().state(), v1::Analysis::SUCCEEDED) << a_seen.back().error().message();
  const v1::AnalysisReport& a_report = a_seen.back().report();

  grpc::ClientContext context;
  v1::CreateAnalysisRequest request;
  request.mutable_analysis()->set_run(run);
  request.mutable_analysis()->set_base_analysis(a.name());
  request.mutable_analysis()->mutable_model()->add_effects("acc_scale_factor.z");
  v1::Analysis b;
  const grpc::Status status = analyses_->CreateAnalysis(&context, request, &b);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(b.base_analysis(), a.name());
  EXPECT_THAT(std::vector<std::string>(b.baseline().effects().begin(), b.baseline().effects().end()),
              ::testing::ElementsAreArray(a_report.model().effects()));
  const auto b_seen = Watch(b.name());
  ASSERT_FALSE(b_seen.empty());
  ASSERT_EQ(b_seen.back().state(), v1::Analysis::SUCCEEDED) << b_seen.back().error().message();
  const v1::AnalysisReport& b_report = b_seen.back().report();
  // Model A is the earlier analysis's, not identified again.
  EXPECT_TRUE(std::any_of(b_report.decisions().begin(), b_report.decisions().end(), [](const v1::Decision& d) {
    return d.kind() == v1::Decision::A_PRIORI_MODEL &&
           std::find(d.qualifiers().begin(), d.qualifiers().end(), "earlier_analysis") != d.qualifiers().end();
  }));
  ASSERT_TRUE(b_report.has_comparison());
  EXPECT_EQ(b_report.comparison().log_likelihood_before(), a_report.log_likelihood());
  EXPECT_THAT(b_report.model().effects(), ::testing::Contains("acc_scale_factor.z"));

  // Refused, naming the field: another run's analysis, one that has not
  // succeeded, a baseline outside its model, a name that is no analysis's.
  const std::string other_run = Upload(SimulatedRun("INS-E2E-ADD-2", "static", 10.0));
  const v1::Analysis queued = Create(other_run);
  const auto refusal = [&](const std::string& on_run, const std::string& base, const std::string& baseline) {
    grpc::ClientContext c;
    v1::CreateAnalysisRequest r;
    r.mutable_analysis()->set_run(on_run);
    r.mutable_analysis()->set_base_analysis(base);
    if (!baseline.empty()) r.mutable_analysis()->mutable_baseline()->add_effects(baseline);
    v1::Analysis ignored;
    return analyses_->CreateAnalysis(&c, r, &ignored);
  };
  grpc::Status refused = refusal(other_run, a.name(), "");
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(refused.error_message(), HasSubstr("analysis.base_analysis"));
  refused = refusal(other_run, queued.name(), "");
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << refused.error_message();
  EXPECT_THAT(refused.error_message(), HasSubstr("has not succeeded"));
  refused = refusal(run, a.name(), "gyro_scale_factor");
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(refused.error_message(), HasSubstr("analysis.baseline.effects[0]"));
  refused = refusal(run, "runs/x", "");
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(refused.error_message(), HasSubstr("analysis.base_analysis"));
  // Through REST, with the JSON name.
  auto rest = http().Post("/v1/analyses",
                          "{\"run\":\"" + run + "\",\"baseAnalysis\":\"" + a.name() +
                              "\",\"model\":{\"effects\":[\"acc_scale_factor.y\"]}}",
                          "application/json");
  ASSERT_TRUE(rest);
  EXPECT_EQ(rest->status, 200) << rest->body;
  EXPECT_THAT(rest->body, HasSubstr("\"baseAnalysis\":\"" + a.name() + "\""));
}

TEST_F(AnalysesTest, AHealthyUnitsTopHypothesisIsHealthy) {
  const v1::Diagnosis d = DiagnoseRun(SimulatedRun("INS-E2E-2", "static", 10.0));
  ASSERT_GT(d.candidates_size(), 0);
  EXPECT_EQ(d.candidates(0).module(), "healthy") << d.DebugString();
  // Through REST too, and the diagnosis can be read back.
  auto rest = http().Get(("/v1/" + d.name()).c_str());
  ASSERT_TRUE(rest);
  EXPECT_EQ(rest->status, 200);
  EXPECT_THAT(rest->body, HasSubstr("\"candidates\""));
}

TEST_F(AnalysesTest, AGyroXTorquerScaleFactorShiftRanksGyroXFirst) {
  // One axis's scale factor: the gyro's own torquer, not the interface card
  // that scales every axis together.
  const double shift = 10.0 * Nominal("gyro_scale_factor.x") + 5.0 * Tolerance("gyro_scale_factor.x");
  const v1::Diagnosis d =
      DiagnoseRun(SimulatedRun("INS-E2E-3", "full", 10.0, {}, "gyro_scale_factor.x=" + std::to_string(shift)));
  ASSERT_GT(d.candidates_size(), 0);
  EXPECT_EQ(d.candidates(0).module(), "gyro.x") << d.DebugString();
  EXPECT_EQ(d.candidates(0).failure_mode(), "failureModes/dtg-torquer-scale-shift.x") << d.DebugString();
}

TEST_F(AnalysesTest, ATripledGyroXDriftSigmaRanksGyroXFirst) {
  // A worn DTG rotor bearing: the drift's σ of one gyro three times its
  // nominal. Its correlation time stays; an eight-hour drift test (the
  // `drift` profile) spans enough correlation times for the likelihood to
  // tell σ (a two-hour run does not: docs/IDENTIFICATION.md).
  const double sigma = 3.0 * Nominal("gyro_bias_gm.x.sigma");
  const v1::Diagnosis d = DiagnoseRun(SimulatedRun("INS-E2E-5", "drift", 10.0, {{"gyro_bias_gm.x.sigma", sigma}}));
  ASSERT_GT(d.candidates_size(), 0);
  EXPECT_EQ(d.candidates(0).module(), "gyro.x") << d.DebugString();
  EXPECT_EQ(d.candidates(0).failure_mode(), "failureModes/dtg-bearing-wear.x") << d.DebugString();
}

TEST_F(AnalysesTest, ACommonGyroScaleFactorShiftRanksTheInterfaceCardFirst) {
  const v1::Diagnosis d = DiagnoseRun(SimulatedRun("INS-E2E-4", "full", 10.0, {}, "gyro_scale_factor=5e-4"));
  ASSERT_GT(d.candidates_size(), 0);
  EXPECT_EQ(d.candidates(0).module(), "interface_card") << d.DebugString();
}

// Real insdiagd processes on the test's database, one analysis job queued
// for them: killed or stopped mid-job, another completes the job.
class WorkerKillTest : public DatabaseTest {
 protected:
  void TearDown() override {
    if (!dir_.empty()) std::filesystem::remove_all(dir_);
    DatabaseTest::TearDown();
  }

  // Stores `run` and queues its analysis; the job's id.
  std::string QueueAnalysis(const engine::BenchRun& run) {
    kb::RunStore runs(pool());
    auto stored = runs.Create(run, {.sha256 = "x", .request_id = "", .request_fingerprint = ""});
    EXPECT_TRUE(stored.ok()) << stored.status();
    if (!stored.ok()) return "";
    auto created = kb::AnalysisStore(pool()).Create(stored->id, server::EncodedSpec(v1::AnalysisSpec()), "");
    EXPECT_TRUE(created.ok()) << created.status();
    return created.ok() ? api::IdOrSelf(created->name, api::kAnalyses) : "";
  }

  // An insdiagd with one worker, its files under a directory named `tag`.
  Subprocess Start(const std::string& tag, const std::string& lease_seconds) {
    if (dir_.empty()) dir_ = MakeTempDir("insdiag-workers");
    std::filesystem::create_directories(dir_ / tag);
    auto process =
        Subprocess::Start({INSDIAGD_PATH, "--database-url", database_url(), "--data-dir",
                           (dir_ / tag / "data").string(), "--grpc-port", "0", "--http-port", "0",
                           "--bind", "127.0.0.1", "--workers", "1", "--lease-seconds",
                           lease_seconds, "--fleet-refresh-seconds", "0"},
                          dir_ / tag);
    EXPECT_TRUE(process.ok()) << process.status();
    return std::move(*process);
  }

  v1::Analysis Job(const std::string& id, bool with_report = false) {
    auto a = kb::AnalysisStore(pool()).Get(id, with_report);
    EXPECT_TRUE(a.ok()) << a.status();
    return a.ok() ? server::ToProto(*a) : v1::Analysis();
  }

  // Polls until `process`'s worker holds job `id` (RUNNING).
  void WaitUntilRunning(const std::string& id, const Subprocess& process) {
    v1::Analysis a;
    const bool running = testing::PollUntil(
        [&] {
          a = Job(id);
          return a.state() == v1::Analysis::RUNNING || a.state() == v1::Analysis::SUCCEEDED;
        },
        60s, 10ms);
    ASSERT_TRUE(running) << process.Stderr();
    ASSERT_NE(a.state(), v1::Analysis::SUCCEEDED) << "the job finished before it could be reached";
  }

  // Polls until job `id` has ended (SUCCEEDED or FAILED), within `timeout`.
  v1::Analysis WaitUntilEnded(const std::string& id, const Subprocess& process,
                              std::chrono::seconds timeout) {
    v1::Analysis a;
    const bool ended = testing::PollUntil(
        [&] {
          a = Job(id, true);
          return a.state() == v1::Analysis::SUCCEEDED || a.state() == v1::Analysis::FAILED;
        },
        timeout, 50ms);
    if (!ended) ADD_FAILURE() << "job " << id << " did not end within " << timeout.count() << " s\n" << process.Stderr();
    return a;
  }

  std::filesystem::path dir_;
};

TEST_F(WorkerKillTest, AJobWhoseWorkerWasKilledIsCompletedByAnotherProcess) {
  const std::string id = QueueAnalysis(SimulatedRun("INS-KILL-1", "full", 100.0));
  ASSERT_FALSE(id.empty());
  auto first = Start("first", "2");
  // Kill it as soon as its worker holds the job.
  WaitUntilRunning(id, first);
  if (HasFatalFailure()) return;
  first.Signal(SIGKILL);
  ASSERT_TRUE(first.Wait(10s).has_value());
  EXPECT_EQ(Job(id).state(), v1::Analysis::RUNNING) << "killed mid-job, the row still says RUNNING";

  auto second = Start("second", "2");
  // The whole analysis of a two-hour 100 Hz run: a minute here, more on a
  // slow machine beside another test (the same allowance as Watch).
  const v1::Analysis done = WaitUntilEnded(id, second, 480s);
  EXPECT_EQ(done.state(), v1::Analysis::SUCCEEDED) << done.error().message() << "\n" << second.Stderr();
  EXPECT_EQ(done.attempts(), 2);
  EXPECT_EQ(done.report().channels_size(), 9);  // position, velocity, attitude
  second.Signal(SIGTERM);
  second.Wait(20s);
}

// SIGTERM while a worker runs a job: the server stops claiming, finishes or
// releases the job, and exits 0. The job is never left RUNNING under a
// lease nobody holds; released, another process completes it.
TEST_F(WorkerKillTest, SigtermWhileAJobRunsEndsTheJobFinishedOrReleasedAndTheServerExitsCleanly) {
  const std::string id = QueueAnalysis(SimulatedRun("INS-TERM-1", "full", 20.0));
  ASSERT_FALSE(id.empty());
  auto first = Start("first", "30");
  WaitUntilRunning(id, first);
  if (HasFatalFailure()) return;
  first.Signal(SIGTERM);
  // The worker may finish the analysis first: the whole of it, on a slow machine.
  const std::optional<int> exit_status = first.Wait(480s);
  ASSERT_TRUE(exit_status.has_value()) << "insdiagd did not stop on SIGTERM while a job ran\n"
                                       << first.Stderr();
  EXPECT_EQ(*exit_status, 0) << first.Stderr();
  EXPECT_THAT(first.Stderr(), HasSubstr("SIGTERM, shutting down"));

  v1::Analysis after = Job(id, true);
  EXPECT_TRUE(after.state() == v1::Analysis::SUCCEEDED || after.state() == v1::Analysis::QUEUED)
      << "after SIGTERM the job is " << v1::Analysis::State_Name(after.state());
  if (after.state() == v1::Analysis::QUEUED) {
    // Released: another process takes it up at once (no lease to wait out).
    auto second = Start("second", "30");
    after = WaitUntilEnded(id, second, 480s);
    second.Signal(SIGTERM);
    EXPECT_EQ(second.Wait(480s), std::optional<int>(0));
  }
  EXPECT_EQ(after.state(), v1::Analysis::SUCCEEDED) << after.error().message();
  EXPECT_EQ(after.report().channels_size(), 9);  // position, velocity, attitude
}

}  // namespace
}  // namespace insdiag::testing
