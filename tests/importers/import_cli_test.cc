// `insdiag import` and `insdiag join` through the real CLI: a side file in
// either form gives the same run and is refused naming its line and key; the
// join refuses a file of another unit; and `--upload` sends the real record to
// a real insdiagd on the test's database, where the stored run is the
// imported one, sample for sample (its SHA-256). And `insdiag report` of the
// server's analysis shows which identified parameters the run tells.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include <absl/strings/str_cat.h>

#include "insdiag/api/run_codec.h"
#include "insdiag/benchrun/bench_run_csv.h"
#include "insdiag/client/run_client.h"
#include "insdiag/importers/bench_run_import.h"
#include "insdiag/v1/analyses.grpc.pb.h"
#include "insdiag/v1/runs.grpc.pb.h"
#include "support/insdiagd_fixture.h"
#include "support/subprocess.h"

namespace insdiag::testing {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;

constexpr char kRealRecord[] = INSDIAG_SOURCE_DIR "/data/real/rlg-static-psins.imu";

Completed Insdiag(std::vector<std::string> args, const std::filesystem::path& dir) {
  args.insert(args.begin(), INSDIAG_CLI_PATH);
  auto done = RunToCompletion(args, dir, 120s);
  EXPECT_TRUE(done.ok()) << done.status();
  return done.ok() ? *done : Completed{};
}

void Write(const std::filesystem::path& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

// A bench's log: a millisecond clock, rates in deg/h, forces in g; a header line.
std::string BenchLog() {
  std::string log = "time_ms;wx;wy;wz;fx;fy;fz\n";
  for (int k = 1; k <= 300; ++k) log += std::to_string(10 * k) + ";1.5;-2.0;0.5;0.001;-0.002;-0.9995\n";
  return log;
}

class ImportCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = MakeTempDir("insdiag-import-cli");
    Write(dir_ / "bench.csv", BenchLog());
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
};

TEST_F(ImportCliTest, ASideFileInYamlOrJsonGivesTheSameRunAndTheCommandLineWins) {
  Write(dir_ / "side.yaml",
        "# bench 3\n"
        "unit_serial: INS-2000-0042\n"
        "unit_type: INS-2000\n"
        "site_latitude_deg: 55.5672\n"
        "site_longitude_deg: 38.15\n"
        "site_height_m: 125\n"
        "columns: t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z\n"
        "units: gyro=deg/h,acc=g,t=ms\n"
        "delimiters: ';'\n"
        "skip_lines: 1\n");
  Write(dir_ / "side.json",
        "{\n"
        "  \"unit_serial\": \"INS-2000-0042\", \"unit_type\": \"INS-2000\",\n"
        "  \"site_latitude_deg\": 55.5672, \"site_longitude_deg\": 38.15, \"site_height_m\": 125,\n"
        "  \"columns\": \"t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z\",\n"
        "  \"units\": \"gyro=deg/h,acc=g,t=ms\",\n"
        "  \"delimiters\": \";\",\n"
        "  \"skip_lines\": 1\n"
        "}\n");
  std::vector<engine::BenchRun> runs;
  for (const char* side : {"side.yaml", "side.json"}) {
    const auto out = dir_ / (std::string(side) + ".run.csv");
    const Completed done = Insdiag({"import", (dir_ / "bench.csv").string(), "--settings", (dir_ / side).string(),
                                    "-o", out.string()},
                                   dir_);
    ASSERT_EQ(done.exit_status, 0) << side << ": " << done.stderr_text;
    EXPECT_THAT(done.stdout_text, HasSubstr(": 300 samples, 3 s"));
    auto run = benchrun::ReadBenchRunFile(out);
    ASSERT_TRUE(run.ok()) << run.status();
    runs.push_back(*std::move(run));
  }
  ASSERT_EQ(runs[0].samples.size(), runs[1].samples.size());
  for (std::size_t k = 0; k < runs[0].samples.size(); ++k) {
    ASSERT_EQ(runs[0].samples[k].acc_mps2, runs[1].samples[k].acc_mps2) << k;
    ASSERT_EQ(runs[0].samples[k].gyro_rad_s, runs[1].samples[k].gyro_rad_s) << k;
  }
  EXPECT_EQ(runs[1].metadata.unit_serial, "INS-2000-0042");
  EXPECT_EQ(runs[1].metadata.unit_type, "INS-2000");
  EXPECT_NEAR(runs[1].samples.front().acc_mps2.z(), -0.9995 * 9.80665, 1e-12);

  // An option overrides the side file.
  const auto over = dir_ / "override.csv";
  const Completed overridden = Insdiag({"import", (dir_ / "bench.csv").string(), "--settings",
                                        (dir_ / "side.json").string(), "--serial", "INS-2000-0043", "-o", over.string()},
                                       dir_);
  ASSERT_EQ(overridden.exit_status, 0) << overridden.stderr_text;
  auto run = benchrun::ReadBenchRunFile(over);
  ASSERT_TRUE(run.ok()) << run.status();
  EXPECT_EQ(run->metadata.unit_serial, "INS-2000-0043");
}

TEST_F(ImportCliTest, ASideFileIsRefusedNamingItsLineAndKeyAndNothingIsWritten) {
  struct Case {
    const char* name;
    const char* text;
    std::string message;
  };
  const Case cases[] = {
      {"side.json", "{\n  \"unit_serial\": \"A\",\n  \"site_height_m\": null\n}\n",
       ":3:20: site_height_m: is null: leave the key out instead"},
      {"nested.json", "{\"site\": {\"latitude_deg\": 55.5}}", ":1:10: site: is an object or an array"},
      {"side.yaml", "unit_serial: A\nsite:\n  latitude_deg: 55.5\n", ":2:1: site: has no value"},
      {"typo.yaml",
       "unit_serial: A\nsite_latitude_deg: 1\nsite_longitude_deg: 2\nsite_height_m: 3\ncolums: t,gyro_x\n",
       ":5:1: colums: is not a setting of an import"},
  };
  for (const Case& c : cases) {
    const auto side = dir_ / c.name;
    Write(side, c.text);
    const auto out = dir_ / "never.csv";
    const Completed done = Insdiag({"import", (dir_ / "bench.csv").string(), "--settings", side.string(),
                                    "--columns", "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z", "-o", out.string()},
                                   dir_);
    EXPECT_EQ(done.exit_status, 1) << c.name << ": a refused input, not bad usage";
    EXPECT_THAT(done.stderr_text, HasSubstr(side.string() + c.message)) << c.name;
    EXPECT_FALSE(std::filesystem::exists(out)) << c.name;
  }
}

TEST_F(ImportCliTest, JoinMakesSegmentsOfOneUnitsFilesAndRefusesAnothersNamingTheFile) {
  std::vector<std::string> files;
  for (const char* serial : {"INS-1", "INS-1", "INS-2"}) {
    files.push_back((dir_ / absl::StrCat("part-", files.size() + 1, ".csv")).string());
    const Completed done = Insdiag({"import", (dir_ / "bench.csv").string(), "--columns",
                                    "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z", "--units", "gyro=deg/h,acc=g,t=ms",
                                    "--set", "delimiters=;", "--set", "skip_lines=1", "--serial", serial, "--site",
                                    "55.5672,38.15,125", "-o", files.back()},
                                   dir_);
    ASSERT_EQ(done.exit_status, 0) << done.stderr_text;
  }
  const auto joined = dir_ / "test.csv";
  const Completed two = Insdiag({"join", files[0], files[1], "-o", joined.string()}, dir_);
  ASSERT_EQ(two.exit_status, 0) << two.stderr_text;
  EXPECT_THAT(two.stdout_text, HasSubstr(": 2 segments, 600 samples"));
  auto run = benchrun::ReadBenchRunFile(joined);
  ASSERT_TRUE(run.ok()) << run.status();
  EXPECT_EQ(run->metadata.format, benchrun::kFormatV2);
  EXPECT_EQ(run->metadata.segment_starts, (std::vector<std::size_t>{300}));
  EXPECT_NEAR(run->samples[300].t_s, 3.01, 1e-9) << "the second file follows the first by one interval";

  const Completed other = Insdiag({"join", files[0], files[2], "-o", (dir_ / "refused.csv").string()}, dir_);
  EXPECT_EQ(other.exit_status, 1);
  EXPECT_THAT(other.stderr_text, HasSubstr(files[2] + ": unit_serial: another unit (INS-2)"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "refused.csv"));
}

// `insdiag import --upload` against the real insdiagd: the real record, read
// through the psins-imu preset, stored as the run the importer makes of it.
class ImportUploadTest : public ServerProcessTest {
 protected:
  void SetUp() override {
    DatabaseTest::SetUp();
    if (IsSkipped() || HasFatalFailure()) return;
    StartServer(INSDIAGD_PATH, "insdiag-import-upload");
  }
};
using ReportCliTest = ImportUploadTest;

TEST_F(ImportUploadTest, TheStoredRunIsTheImportedRealRecordSampleForSample) {
  const std::vector<std::string> import = {"import", kRealRecord, "--preset", "psins-imu", "--serial",
                                           "PSINS-RLG-2014", "--upload", "--server", address_};
  // Without a token the server refuses, and nothing is stored.
  const Completed anonymous = Insdiag(import, dir_);
  EXPECT_EQ(anonymous.exit_status, 1);
  EXPECT_THAT(anonymous.stderr_text, HasSubstr("UNAUTHENTICATED"));

  std::vector<std::string> with_token = import;
  with_token.insert(with_token.end(), {"--token", token_, "--request-id", "import-upload-test-1"});
  const Completed uploaded = Insdiag(with_token, dir_);
  ASSERT_EQ(uploaded.exit_status, 0) << uploaded.stderr_text;
  std::smatch name;
  ASSERT_TRUE(std::regex_match(uploaded.stdout_text, name, std::regex(R"((runs/[0-9a-f-]{36})\n)")))
      << uploaded.stdout_text;

  // The same import in this process, as the CLI makes it.
  importers::ImportSettings settings;
  settings.Set("preset", "psins-imu", {"test", 0, 0, "preset"});
  settings.Set("unit_serial", "PSINS-RLG-2014", {"test", 0, 0, "unit_serial"});
  auto imported = importers::ImportBenchRunFile(kRealRecord, settings);
  ASSERT_TRUE(imported.ok()) << imported.status();

  auto stub = v1::RunService::NewStub(client::Connect(address_, token_));
  grpc::ClientContext context;
  v1::GetRunRequest request;
  request.set_name(name[1].str());
  v1::Run stored;
  const grpc::Status got = stub->GetRun(&context, request, &stored);
  ASSERT_TRUE(got.ok()) << got.error_message();
  EXPECT_EQ(stored.sample_count(), 184718);
  EXPECT_EQ(stored.sample_count(), static_cast<std::int64_t>(imported->samples.size()));
  EXPECT_EQ(stored.sha256(), api::SampleSha256(*imported)) << "the stored samples are not the imported ones";
  EXPECT_NEAR(stored.nominal_interval_s(), 0.01, 1e-12);
  EXPECT_EQ(stored.metadata().unit_serial(), "PSINS-RLG-2014");
  EXPECT_NEAR(stored.metadata().site().latitude_deg(), 34.246048, 1e-9);
  EXPECT_NEAR(stored.metadata().site().height_m(), 380.0, 1e-9);
  std::map<std::string, std::string> extra;
  for (const v1::MetadataEntry& e : stored.metadata().extra()) extra[e.key()] = e.value();
  EXPECT_THAT(extra["imported_from"], HasSubstr("psins-imu preset"));
  EXPECT_THAT(extra["reference_attitude"], HasSubstr("levelled"));

  // Again with the same request id: the run stored the first time, not a second one.
  const Completed again = Insdiag(with_token, dir_);
  ASSERT_EQ(again.exit_status, 0) << again.stderr_text;
  EXPECT_EQ(again.stdout_text, uploaded.stdout_text);
  grpc::ClientContext list_context;
  v1::ListRunsRequest list;
  list.set_unit_serial("PSINS-RLG-2014");
  v1::ListRunsResponse listed;
  ASSERT_TRUE(stub->ListRuns(&list_context, list, &listed).ok());
  EXPECT_EQ(listed.runs_size(), 1);
}

// A level, still run analysed by the server with the accelerometers' scale
// factors in the model: the stored report carries each one's observability,
// and `insdiag report` prints it — x and y saw no force.
TEST_F(ReportCliTest, TheReportSaysWhichIdentifiedParametersTheRunTells) {
  const auto file = dir_ / "still.csv";
  const Completed simulated = Insdiag({"simulate", file.string(), "--profile", "static", "--rate", "10", "--seed", "5",
                                       "--serial", "INS-OBS-1"},
                                      dir_);
  ASSERT_EQ(simulated.exit_status, 0) << simulated.stderr_text;
  const Completed uploaded = Insdiag({"upload", file.string(), "--server", address_, "--token", token_}, dir_);
  ASSERT_EQ(uploaded.exit_status, 0) << uploaded.stderr_text;
  const std::string run = uploaded.stdout_text.substr(0, uploaded.stdout_text.find('\n'));

  auto stub = v1::AnalysisService::NewStub(client::Connect(address_, token_));
  v1::CreateAnalysisRequest create;
  create.mutable_analysis()->set_run(run);
  create.mutable_analysis()->mutable_model()->add_effects("acc_scale_factor");
  v1::Analysis analysis;
  {
    grpc::ClientContext context;
    const grpc::Status created = stub->CreateAnalysis(&context, create, &analysis);
    ASSERT_TRUE(created.ok()) << created.error_message();
  }
  // Poll with a deadline until the server's worker has run it.
  const auto deadline = std::chrono::steady_clock::now() + 240s;
  while (analysis.state() != v1::Analysis::SUCCEEDED && analysis.state() != v1::Analysis::FAILED &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(500ms);
    grpc::ClientContext context;
    v1::GetAnalysisRequest get;
    get.set_name(analysis.name());
    ASSERT_TRUE(stub->GetAnalysis(&context, get, &analysis).ok());
  }
  ASSERT_EQ(analysis.state(), v1::Analysis::SUCCEEDED) << analysis.error().message();
  std::map<std::string, v1::IdentifiedParameter::Observability> verdicts;
  for (const v1::IdentifiedParameter& p : analysis.report().identified()) verdicts[p.name()] = p.observability();
  for (const char* name : {"acc_scale_factor.x", "acc_scale_factor.y", "gyro_arw.x"}) {
    ASSERT_TRUE(verdicts.contains(name)) << name << " is not in the report";
  }
  EXPECT_EQ(verdicts["acc_scale_factor.x"], v1::IdentifiedParameter::NOT_EXCITED);
  EXPECT_EQ(verdicts["acc_scale_factor.y"], v1::IdentifiedParameter::NOT_EXCITED);
  EXPECT_EQ(verdicts["gyro_arw.x"], v1::IdentifiedParameter::OBSERVABILITY_UNSPECIFIED) << "an Allan term is not judged";

  const Completed text = Insdiag({"report", analysis.name(), "--server", address_, "--token", token_}, dir_);
  ASSERT_EQ(text.exit_status, 0) << text.stderr_text;
  EXPECT_THAT(text.stdout_text, HasSubstr("observability"));
  EXPECT_THAT(text.stdout_text, ::testing::ContainsRegex("acc_scale_factor\\.x .*NOT observable: not excited, the test "
                                                         "never excited it"));
  const Completed json = Insdiag({"report", analysis.name(), "--json", "--server", address_, "--token", token_}, dir_);
  ASSERT_EQ(json.exit_status, 0) << json.stderr_text;
  EXPECT_THAT(json.stdout_text, HasSubstr("\"observability\": \"NOT_EXCITED\""));
}

}  // namespace
}  // namespace insdiag::testing
