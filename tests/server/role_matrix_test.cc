// Who may do what, over every method the server serves, through a real gRPC
// channel and a real HTTP client: each role makes a valid call of every
// method (a stored run, a succeeded analysis, a diagnosis, a failure record,
// an ended live test and fresh resources to delete, cancel, resolve and
// revoke); below the method's least role it is refused with
// PERMISSION_DENIED / 403 naming that role, at and above it succeeds. Every
// call of a writing method, admitted or refused, leaves exactly its audit
// event; a read leaves none. The methods come from the proto files, so a new
// service or method without a case here fails the test.
#include <absl/strings/numbers.h>
#include <absl/strings/str_cat.h>
#include <absl/strings/str_split.h>
#include <gmock/gmock.h>
#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <regex>
#include <set>
#include <sstream>
#include <thread>

#include "generic_call.h"
#include "google/api/annotations.pb.h"
#include "insdiag/api/json.h"
#include "insdiag/api/run_codec.h"
#include "insdiag/benchrun/bench_run_csv.h"
#include "insdiag/client/unary.h"
#include "insdiag/v1/access.grpc.pb.h"
#include "insdiag/v1/fleet.grpc.pb.h"
#include "insdiag/v1/knowledge.grpc.pb.h"
#include "insdiag/v1/live.grpc.pb.h"
#include "rest_form.h"
#include "server_fixture.h"
#include "support/synthetic_run.h"

namespace insdiag::testing {
namespace {

using namespace std::chrono_literals;
using google::protobuf::FieldDescriptor;
using google::protobuf::Message;
using google::protobuf::MethodDescriptor;
using ::testing::HasSubstr;

constexpr v1::Role kRoles[] = {v1::VIEWER, v1::OPERATOR, v1::ENGINEER, v1::ADMIN};
constexpr char kUnit[] = "units/INS-2000-0042";  // SyntheticStaticRun's unit
constexpr char kModule[] = "units/INS-2000-0042/modules/gyro.x";
constexpr char kParameter[] = "gyro_bias_gm.x.sigma";

// Every service declared in proto/insdiag/v1/*.proto, read from the files
// themselves: a service added there is found here whether or not it is served.
std::set<std::string> ServicesOfTheProtoFiles() {
  std::set<std::string> services;
  const std::regex service(R"(^service\s+(\w+)\s*\{)");
  for (const auto& entry :
       std::filesystem::directory_iterator(INSDIAG_SOURCE_DIR "/proto/insdiag/v1")) {
    if (entry.path().extension() != ".proto") continue;
    std::ifstream in(entry.path());
    std::string line;
    while (std::getline(in, line)) {
      std::smatch m;
      if (std::regex_search(line, m, service)) services.insert("insdiag.v1." + m[1].str());
    }
  }
  return services;
}

std::vector<const MethodDescriptor*> EveryServedMethod() {
  std::vector<const MethodDescriptor*> methods;
  for (const std::string& name : server::InsdiagServer::ServiceNames()) {
    const auto* service =
        google::protobuf::DescriptorPool::generated_pool()->FindServiceByName(name);
    EXPECT_NE(service, nullptr) << name;
    if (service == nullptr) continue;
    for (int m = 0; m < service->method_count(); ++m) methods.push_back(service->method(m));
  }
  return methods;
}

std::string GrpcPath(const MethodDescriptor* method) {
  return "/" + method->service()->full_name() + "/" + method->name();
}

// One valid call of a method, made afresh for each caller: the requests
// (one for a unary method, the stream's messages in order for a streaming
// one), its REST form, and what its audit event must name.
struct Call {
  std::vector<std::string> requests;  // serialized
  std::optional<RestRequest> rest;  // the http rule's form, unless the method's case gives its own
  // The resource the audit event of an admitted call names: exactly, when
  // the request names it; else the collection of the resource it creates.
  std::string resource;
  std::string resource_collection;
};

// Builds a Call of one method from its request message.
struct CallBuilder {
  const MethodDescriptor* method;
  Call call;
  // A unary request, and its REST form from the method's http rule.
  void Unary(const Message& request) {
    call.requests = {request.SerializeAsString()};
    call.rest = RestFormOf(method, request);
  }
  // A writing request that names the resource it acts on: its audit event must name it.
  void Named(const Message& request, const std::string& resource) {
    Unary(request);
    call.resource = resource;
  }
};

class RoleMatrixTest : public ServerTest {
 protected:
  void SetUp() override {
    ServerTest::SetUp();
    if (IsSkipped() || HasFatalFailure()) return;
    for (v1::Role role : kRoles) {
      const std::string display_name = "matrix " + v1::Role_Name(role);
      const std::string secret = MakeToken(pool(), role, display_name);
      callers_[role] = {display_name, client::Connect(GrpcAddress(), secret),
                        std::make_unique<httplib::Client>("127.0.0.1", server_->http_port())};
      callers_[role].http->set_bearer_token_auth(secret.c_str());
      callers_[role].http->set_read_timeout(60s);
    }
    BuildWorld();
  }

  std::string GrpcAddress() const { return "127.0.0.1:" + std::to_string(server_->grpc_port()); }

  // What the calls read: a run and its succeeded analysis, a diagnosis, a
  // failure record, a test recorded live and ended, the unit's type and a
  // failure mode. Made by the admin.
  void BuildWorld() {
    run_ = FreshRun(500, 3);
    analysis_ = FreshAnalysis();
    ASSERT_FALSE(analysis_.empty());
    auto analyses = v1::AnalysisService::NewStub(channel());
    v1::Analysis analysis;
    const auto deadline = std::chrono::steady_clock::now() + 180s;
    do {
      ASSERT_LT(std::chrono::steady_clock::now(), deadline) << analysis_ << " did not end";
      std::this_thread::sleep_for(100ms);
      v1::GetAnalysisRequest get;
      get.set_name(analysis_);
      auto got = client::CallUnary<v1::Analysis>([&](grpc::ClientContext* c, v1::Analysis* r) {
        return analyses->GetAnalysis(c, get, r);
      });
      ASSERT_TRUE(got.ok()) << got.status();
      analysis = *got;
    } while (analysis.state() == v1::Analysis::QUEUED || analysis.state() == v1::Analysis::RUNNING);
    ASSERT_EQ(analysis.state(), v1::Analysis::SUCCEEDED) << analysis.error().message();
    diagnosis_ = FreshDiagnosis();
    ASSERT_FALSE(diagnosis_.empty());

    auto knowledge = v1::KnowledgeService::NewStub(channel());
    v1::CreateFailureRecordRequest record;
    *record.mutable_failure_record() = NoFaultFoundRecord(120.0);
    auto made =
        client::CallUnary<v1::FailureRecord>([&](grpc::ClientContext* c, v1::FailureRecord* r) {
          return knowledge->CreateFailureRecord(c, record, r);
        });
    ASSERT_TRUE(made.ok()) << made.status();
    record_ = made->name();
    v1::GetUnitRequest get_unit;
    get_unit.set_name(kUnit);
    auto unit = client::CallUnary<v1::Unit>(
        [&](grpc::ClientContext* c, v1::Unit* r) { return knowledge->GetUnit(c, get_unit, r); });
    ASSERT_TRUE(unit.ok()) << unit.status();
    unit_type_ = unit->unit_type();
    ASSERT_FALSE(unit_type_.empty());
    v1::ListFailureModesRequest modes;
    modes.set_unit_type(unit_type_);
    auto listed = client::CallUnary<v1::ListFailureModesResponse>(
        [&](grpc::ClientContext* c, v1::ListFailureModesResponse* r) {
          return knowledge->ListFailureModes(c, modes, r);
        });
    ASSERT_TRUE(listed.ok()) << listed.status();
    modes.set_module_role("gyro.x");
    listed = client::CallUnary<v1::ListFailureModesResponse>(
        [&](grpc::ClientContext* c, v1::ListFailureModesResponse* r) {
          return knowledge->ListFailureModes(c, modes, r);
        });
    ASSERT_TRUE(listed.ok()) << listed.status();
    ASSERT_GT(listed->failure_modes_size(), 0);
    failure_mode_ = listed->failure_modes(0).name();
    // Two gyros (of two units) failed at different ages: what a Weibull fit needs.
    engine::BenchRun other_unit = SyntheticStaticRun(200, 50.0, next_seed_++);
    other_unit.metadata.unit_serial = "INS-2000-0043";
    auto other = client::UploadRun(runs(), other_unit, client::UploadOptions{});
    ASSERT_TRUE(other.ok()) << other.status();
    for (const auto& [module, hours] :
         {std::pair(std::string(kModule), 300.0),
          std::pair(std::string("units/INS-2000-0043/modules/gyro.x"), 900.0)}) {
      v1::CreateFailureRecordRequest failure;
      failure.mutable_failure_record()->set_module(module);
      failure.mutable_failure_record()->set_failure_mode(failure_mode_);
      failure.mutable_failure_record()->set_confirmed(true);
      failure.mutable_failure_record()->set_operating_hours(hours);
      failure.mutable_failure_record()->set_repair_action("module replaced");
      auto confirmed =
          client::CallUnary<v1::FailureRecord>([&](grpc::ClientContext* c, v1::FailureRecord* r) {
            return knowledge->CreateFailureRecord(c, failure, r);
          });
      ASSERT_TRUE(confirmed.ok()) << confirmed.status();
    }

    grpc::GenericStub admin(channel());
    const GenericAnswer live =
        CallGeneric(admin, "/insdiag.v1.LiveRunService/MonitorRun", MonitoredTest(next_seed_++));
    ASSERT_TRUE(live.status.ok()) << live.status.error_message();
    ASSERT_FALSE(live.responses.empty());
    v1::LiveRun ended;
    ASSERT_TRUE(ended.ParseFromString(live.responses.back()));
    ASSERT_EQ(ended.state(), v1::LiveRun::STORED) << ended.error().message();
    live_run_ = ended.name();
  }

  v1::FailureRecord NoFaultFoundRecord(double hours) {
    v1::FailureRecord record;
    record.set_module(kModule);
    record.set_operating_hours(hours);
    record.set_no_fault_found(true);
    record.set_notes("suspected on the bench; nothing found");
    return record;
  }

  // A new stored run of `samples` at 50 Hz: samples differ with the seed.
  std::string FreshRun(std::size_t samples = 200, std::uint32_t seed = 0) {
    auto run = client::UploadRun(runs(),
                                 SyntheticStaticRun(samples, 50.0, seed != 0 ? seed : next_seed_++),
                                 client::UploadOptions{});
    EXPECT_TRUE(run.ok()) << run.status();
    return run.ok() ? run->name() : "";
  }

  std::string FreshAnalysis() {
    auto stub = v1::AnalysisService::NewStub(channel());
    v1::CreateAnalysisRequest create;
    create.mutable_analysis()->set_run(run_);
    auto made = client::CallUnary<v1::Analysis>([&](grpc::ClientContext* c, v1::Analysis* r) {
      return stub->CreateAnalysis(c, create, r);
    });
    EXPECT_TRUE(made.ok()) << made.status();
    return made.ok() ? made->name() : "";
  }

  std::string FreshDiagnosis() {
    auto stub = v1::KnowledgeService::NewStub(channel());
    v1::CreateDiagnosisRequest create;
    create.set_analysis(analysis_);
    auto made = client::CallUnary<v1::Diagnosis>([&](grpc::ClientContext* c, v1::Diagnosis* r) {
      return stub->CreateDiagnosis(c, create, r);
    });
    EXPECT_TRUE(made.ok()) << made.status();
    return made.ok() ? made->name() : "";
  }

  std::string FreshToken() {
    kb::AccessStore store(pool());
    kb::Token token;
    token.display_name = "to be revoked";
    token.role = kb::Role::kViewer;
    auto made = store.CreateToken(token, "role matrix");
    EXPECT_TRUE(made.ok()) << made.status();
    return made.ok() ? made->token.name : "";
  }

  // A whole test as the bench streams it: the metadata with its planned
  // duration, sample chunks, the digest.
  std::vector<std::string> MonitoredTest(std::uint32_t seed) {
    const engine::BenchRun run = SyntheticStaticRun(200, 50.0, seed);
    std::vector<std::string> stream;
    api::ForEachUploadRequest(run, "", 50, [&](const v1::UploadRunRequest& upload) {
      v1::MonitorRunRequest request;
      if (stream.empty()) request.set_planned_duration_s(4.0);
      *request.mutable_upload() = upload;
      stream.push_back(request.SerializeAsString());
      return true;
    });
    return stream;
  }

  // A valid call of `method`, made now (resources it consumes are fresh);
  // nullopt when this test has no case for it.
  std::optional<Call> CallOf(const MethodDescriptor* method) {
    CallBuilder b{method, {}};
    const std::string& service = method->service()->name();
    const std::string& name = method->name();
    const bool known = service == "RunService"         ? RunServiceCall(name, b)
                       : service == "AnalysisService"  ? AnalysisServiceCall(name, b)
                       : service == "KnowledgeService" ? KnowledgeServiceCall(name, b)
                       : service == "FleetService"     ? FleetServiceCall(name, b)
                       : service == "AccessService"    ? AccessServiceCall(name, b)
                       : service == "LiveRunService"   ? LiveRunServiceCall(name, b)
                                                       : false;
    if (!known) return std::nullopt;
    return b.call;
  }

  // RunService's methods.
  bool RunServiceCall(const std::string& name, CallBuilder& b) {
    if (name == "UploadRun") {
      const engine::BenchRun run = SyntheticStaticRun(200, 50.0, next_seed_++);
      api::ForEachUploadRequest(run, "", 100, [&](const v1::UploadRunRequest& r) {
        b.call.requests.push_back(r.SerializeAsString());
        return true;
      });
      b.call.rest =
          RestRequest{"POST", "/v1/runs:upload", benchrun::FormatBenchRun(run), "text/csv"};
      b.call.resource_collection = "runs/";
    } else if (name == "GetRun") {
      v1::GetRunRequest r;
      r.set_name(run_);
      b.Unary(r);
    } else if (name == "ListRuns") {
      v1::ListRunsRequest r;
      r.set_page_size(10);
      r.set_unit_serial("INS-2000-0042");
      b.Unary(r);
    } else if (name == "DeleteRun") {
      v1::DeleteRunRequest r;
      r.set_name(FreshRun());
      const std::string deleted = r.name();
      b.Named(r, deleted);
    } else if (name == "ReadRunSamples") {
      v1::ReadRunSamplesRequest r;
      r.set_name(run_);
      r.set_chunk_size(100);
      b.Unary(r);
    } else {
      return false;
    }
    return true;
  }

  // AnalysisService's methods.
  bool AnalysisServiceCall(const std::string& name, CallBuilder& b) {
    if (name == "CreateAnalysis") {
      v1::CreateAnalysisRequest r;
      r.mutable_analysis()->set_run(run_);
      r.mutable_analysis()->mutable_model()->add_effects("gyro_scale_factor.z");
      b.Unary(r);
      b.call.resource_collection = "analyses/";
    } else if (name == "GetAnalysis") {
      v1::GetAnalysisRequest r;
      r.set_name(analysis_);
      b.Unary(r);
    } else if (name == "WatchAnalysis") {
      v1::WatchAnalysisRequest r;
      r.set_name(analysis_);  // succeeded: its state, then the stream ends
      b.Unary(r);
    } else if (name == "ListAnalyses") {
      v1::ListAnalysesRequest r;
      r.set_run(run_);
      r.set_include_reports(true);
      b.Unary(r);
    } else if (name == "CancelAnalysis") {
      v1::CancelAnalysisRequest r;
      r.set_name(FreshAnalysis());
      const std::string cancelled = r.name();
      b.Named(r, cancelled);
    } else if (name == "ReadResidualSeries") {
      v1::ReadResidualSeriesRequest r;
      r.set_name(analysis_);
      r.add_channels("vel_n");
      r.set_chunk_size(1000);
      b.Unary(r);
    } else if (name == "ReadDisplaySeries") {
      v1::ReadDisplaySeriesRequest r;
      r.set_name(analysis_);
      r.set_columns(100);
      b.Unary(r);
    } else if (name == "GetTestReport") {
      v1::GetTestReportRequest r;
      r.set_name(analysis_);
      r.set_diagnosis(diagnosis_);
      b.Unary(r);
    } else {
      return false;
    }
    return true;
  }

  // KnowledgeService's methods.
  bool KnowledgeServiceCall(const std::string& name, CallBuilder& b) {
    if (name == "GetUnitType") {
      v1::GetUnitTypeRequest r;
      r.set_name(unit_type_);
      b.Unary(r);
    } else if (name == "ListUnitTypes") {
      b.Unary(v1::ListUnitTypesRequest());
    } else if (name == "GetUnit") {
      v1::GetUnitRequest r;
      r.set_name(kUnit);
      b.Unary(r);
    } else if (name == "ListUnits") {
      v1::ListUnitsRequest r;
      r.set_unit_type(unit_type_);
      b.Unary(r);
    } else if (name == "ListModules") {
      v1::ListModulesRequest r;
      r.set_parent(kUnit);
      b.Unary(r);
    } else if (name == "GetUnitHistory") {
      v1::GetUnitHistoryRequest r;
      r.set_unit(kUnit);
      b.Unary(r);
    } else if (name == "ListFailureModes") {
      v1::ListFailureModesRequest r;
      r.set_unit_type(unit_type_);
      r.set_module_role("gyro.x");
      b.Unary(r);
    } else if (name == "GetFailureMode") {
      v1::GetFailureModeRequest r;
      r.set_name(failure_mode_);
      b.Unary(r);
    } else if (name == "CreateFailureRecord") {
      v1::CreateFailureRecordRequest r;
      *r.mutable_failure_record() = NoFaultFoundRecord(150.0);
      b.Unary(r);
      b.call.resource_collection = "failureRecords/";
    } else if (name == "CorrectFailureRecord") {
      v1::CorrectFailureRecordRequest r;
      r.set_name(record_);
      *r.mutable_failure_record() = NoFaultFoundRecord(125.0);
      r.set_reason("the hours were misread");
      b.Named(r, record_);
    } else if (name == "ListFailureRecordRevisions") {
      v1::ListFailureRecordRevisionsRequest r;
      r.set_name(record_);
      b.Unary(r);
    } else if (name == "ListFailureRecords") {
      v1::ListFailureRecordsRequest r;
      r.set_unit(kUnit);
      b.Unary(r);
    } else if (name == "CreateDiagnosis") {
      v1::CreateDiagnosisRequest r;
      r.set_analysis(analysis_);
      b.Unary(r);
      b.call.resource_collection = "diagnoses/";
    } else if (name == "GetDiagnosis") {
      v1::GetDiagnosisRequest r;
      r.set_name(diagnosis_);
      b.Unary(r);
    } else if (name == "ListDiagnoses") {
      v1::ListDiagnosesRequest r;
      r.set_unit(kUnit);
      b.Unary(r);
    } else if (name == "ResolveDiagnosis") {
      v1::ResolveDiagnosisRequest r;
      r.set_name(FreshDiagnosis());
      r.set_module("gyro.x");
      r.set_confirmed(false);
      r.set_notes("rejected on the bench");
      const std::string resolved = r.name();
      b.Named(r, resolved);
    } else {
      return false;
    }
    return true;
  }

  // FleetService's methods.
  bool FleetServiceCall(const std::string& name, CallBuilder& b) {
    if (name == "GetFleetStatistics") {
      v1::GetFleetStatisticsRequest r;
      r.set_unit_type(unit_type_);
      b.Unary(r);
    } else if (name == "ListFailureCounts") {
      v1::ListFailureCountsRequest r;
      r.set_period("month");
      b.Unary(r);
    } else if (name == "GetFailurePareto") {
      v1::GetFailureParetoRequest r;
      r.set_unit_type(unit_type_);
      b.Unary(r);
    } else if (name == "GetWeibullFit") {
      v1::GetWeibullFitRequest r;
      r.set_unit_type(unit_type_);
      r.set_module_role("gyro.x");
      b.Unary(r);
    } else if (name == "ListParameterTrends") {
      v1::ListParameterTrendsRequest r;
      r.set_unit_type(unit_type_);
      r.set_parameter(kParameter);
      b.Unary(r);
    } else if (name == "GetParameterTrend") {
      v1::GetParameterTrendRequest r;
      r.set_unit_type(unit_type_);
      r.set_parameter(kParameter);
      b.Unary(r);
    } else if (name == "RankUnits") {
      v1::RankUnitsRequest r;
      r.set_page_size(10);
      b.Unary(r);
    } else {
      return false;
    }
    return true;
  }

  // AccessService's methods.
  bool AccessServiceCall(const std::string& name, CallBuilder& b) {
    if (name == "GetCaller") {
      b.Unary(v1::GetCallerRequest());
    } else if (name == "CreateToken") {
      v1::CreateTokenRequest r;
      r.mutable_token()->set_display_name("bench-7 reader");
      r.mutable_token()->set_role(v1::VIEWER);
      b.Unary(r);
      b.call.resource_collection = "tokens/";
    } else if (name == "ListTokens") {
      b.Unary(v1::ListTokensRequest());
    } else if (name == "RevokeToken") {
      v1::RevokeTokenRequest r;
      r.set_name(FreshToken());
      const std::string revoked = r.name();
      b.Named(r, revoked);
    } else if (name == "ListAuditEvents") {
      v1::ListAuditEventsRequest r;
      r.set_page_size(5);
      b.Unary(r);
    } else {
      return false;
    }
    return true;
  }

  // LiveRunService's methods.
  bool LiveRunServiceCall(const std::string& name, CallBuilder& b) {
    if (name == "MonitorRun") {
      b.call.requests = MonitoredTest(next_seed_++);  // no REST form: requests stream in
      b.call.resource_collection = "runs/";           // the run the ended test stored
    } else if (name == "ListLiveRuns") {
      b.Unary(v1::ListLiveRunsRequest());
    } else if (name == "WatchLiveRun") {
      v1::WatchLiveRunRequest r;
      r.set_name(live_run_);  // ended: its last state, then the stream ends
      b.Unary(r);
    } else {
      return false;
    }
    return true;
  }

  // The audit trail's newest event number (0: none yet).
  std::int64_t NewestAuditEvent() {
    const auto events = AuditEventsAfter(0, 1);
    return events.empty() ? 0 : EventNumber(events.front());
  }

  static std::int64_t EventNumber(const v1::AuditEvent& event) {
    std::int64_t number = 0;
    EXPECT_TRUE(absl::SimpleAtoi(event.name().substr(event.name().find('/') + 1), &number))
        << event.name();
    return number;
  }

  // The events after event `after`, newest first, at most `at_most`.
  std::vector<v1::AuditEvent> AuditEventsAfter(std::int64_t after, int at_most = 10) {
    auto stub = v1::AccessService::NewStub(channel());
    v1::ListAuditEventsRequest request;
    request.set_page_size(at_most);
    auto listed = client::CallUnary<v1::ListAuditEventsResponse>(
        [&](grpc::ClientContext* c, v1::ListAuditEventsResponse* r) {
          return stub->ListAuditEvents(c, request, r);
        });
    EXPECT_TRUE(listed.ok()) << listed.status();
    std::vector<v1::AuditEvent> events;
    if (!listed.ok()) return events;
    for (const auto& e : listed->audit_events()) {
      if (EventNumber(e) > after) events.push_back(e);
    }
    return events;
  }

  // After one call of `method` by `role`: a writing method left exactly one
  // event naming the caller, the method, the resource, the peer and the
  // outcome; a read left none.
  void ExpectAudited(const MethodDescriptor* method, v1::Role role, const Call& call,
                     std::int64_t before, bool admitted, const std::string& transport) {
    const std::string what =
        method->full_name() + " as " + v1::Role_Name(role) + " over " + transport;
    const auto events = AuditEventsAfter(before);
    if (!method->options().GetExtension(v1::access).writes()) {
      EXPECT_TRUE(events.empty()) << what << " is a read, yet left " << events.size()
                                  << " audit events";
      return;
    }
    ASSERT_EQ(events.size(), 1u) << what;
    const v1::AuditEvent& event = events.front();
    EXPECT_EQ(event.method(), method->full_name()) << what;
    EXPECT_EQ(event.display_name(), callers_[role].display_name) << what;
    EXPECT_EQ(event.role(), role) << what;
    EXPECT_THAT(event.token(), ::testing::StartsWith("tokens/")) << what;
    EXPECT_THAT(event.peer(), ::testing::StartsWith("ipv4:127.0.0.1:")) << what;
    EXPECT_TRUE(event.has_event_time()) << what;
    if (!admitted) {
      EXPECT_EQ(event.code(), "PERMISSION_DENIED") << what;
      EXPECT_EQ(event.resource(), "") << what << ": a refused call reached nothing";
      return;
    }
    EXPECT_EQ(event.code(), "OK") << what << ": " << event.message();
    if (!call.resource.empty()) {
      EXPECT_EQ(event.resource(), call.resource) << what;
    } else {
      EXPECT_THAT(event.resource(), ::testing::StartsWith(call.resource_collection)) << what;
      EXPECT_GT(event.resource().size(), call.resource_collection.size()) << what;
    }
  }

  struct Caller {
    std::string display_name;
    std::shared_ptr<grpc::Channel> channel;
    std::unique_ptr<httplib::Client> http;
  };
  std::map<v1::Role, Caller> callers_;
  std::string run_, analysis_, diagnosis_, record_, live_run_, unit_type_, failure_mode_;
  std::uint32_t next_seed_ = 100;
};

TEST(ServedServices, EveryServiceOfTheProtoFilesIsServedAndEveryMethodHasAnAccessRule) {
  const std::set<std::string> declared = ServicesOfTheProtoFiles();
  const auto& served = server::InsdiagServer::ServiceNames();
  EXPECT_GE(declared.size(), 6u);
  EXPECT_EQ(declared, std::set<std::string>(served.begin(), served.end()));
  int methods = 0;
  for (const auto* method : EveryServedMethod()) {
    ++methods;
    ASSERT_TRUE(method->options().HasExtension(v1::access)) << method->full_name();
    EXPECT_NE(method->options().GetExtension(v1::access).role(), v1::ROLE_UNSPECIFIED)
        << method->full_name();
  }
  EXPECT_EQ(methods, 44) << "a method was added or removed: docs/RELIABILITY.md gives the count";
}

// The roles as the product promises them: viewer reads; operator uploads,
// analyses, asks for diagnoses and monitors tests; engineer resolves
// diagnoses, writes failure records and reads the audit trail; admin
// deletes and manages tokens. Each method's declared rule is checked
// against this table, and every other method is a read.
TEST(AccessRules, EachMethodsLeastRoleIsTheOnePromised) {
  const std::map<std::string, v1::Role> promised = {
      {"UploadRun", v1::OPERATOR},
      {"DeleteRun", v1::ADMIN},
      {"CreateAnalysis", v1::OPERATOR},
      {"CancelAnalysis", v1::OPERATOR},
      {"CreateDiagnosis", v1::OPERATOR},
      {"ResolveDiagnosis", v1::ENGINEER},
      {"CreateFailureRecord", v1::ENGINEER},
      {"CorrectFailureRecord", v1::ENGINEER},
      {"CreateToken", v1::ADMIN},
      {"ListTokens", v1::ADMIN},
      {"RevokeToken", v1::ADMIN},
      {"ListAuditEvents", v1::ENGINEER},
      {"MonitorRun", v1::OPERATOR},
  };
  for (const auto* method : EveryServedMethod()) {
    const auto found = promised.find(method->name());
    const v1::Role least = found == promised.end() ? v1::VIEWER : found->second;
    const v1::AccessRule& rule = method->options().GetExtension(v1::access);
    EXPECT_EQ(rule.role(), least) << method->full_name();
    // What changes stored data is exactly what is above a viewer, bar the
    // two reads kept from viewers.
    const bool guarded_read = method->name() == "ListTokens" || method->name() == "ListAuditEvents";
    EXPECT_EQ(rule.writes(), least > v1::VIEWER && !guarded_read) << method->full_name();
  }
}

TEST_F(RoleMatrixTest, EveryMethodRefusesACallerWithoutAValidTokenAndAuditsTheRefusedWrites) {
  grpc::GenericStub anonymous(client::Connect(GrpcAddress(), ""));
  grpc::GenericStub forged(client::Connect(GrpcAddress(), "insdiag_" + std::string(43, 'A')));
  for (const auto* method : EveryServedMethod()) {
    const std::optional<Call> call = CallOf(method);
    ASSERT_TRUE(call.has_value()) << method->full_name() << ": no case in this test";
    const bool writes = method->options().GetExtension(v1::access).writes();
    for (auto* stub : {&anonymous, &forged}) {
      const std::int64_t before = NewestAuditEvent();
      const GenericAnswer answer = CallGeneric(*stub, GrpcPath(method), call->requests);
      EXPECT_EQ(answer.status.error_code(), grpc::StatusCode::UNAUTHENTICATED)
          << method->full_name();
      if (stub == &forged) {
        EXPECT_THAT(answer.status.error_message(), HasSubstr("unknown bearer token"))
            << method->full_name();
      }
      EXPECT_TRUE(answer.responses.empty()) << method->full_name();
      const auto events = AuditEventsAfter(before);
      if (!writes) {
        EXPECT_TRUE(events.empty()) << method->full_name();
        continue;
      }
      ASSERT_EQ(events.size(), 1u) << method->full_name();
      EXPECT_EQ(events[0].method(), method->full_name());
      EXPECT_EQ(events[0].code(), "UNAUTHENTICATED");
      EXPECT_EQ(events[0].token(), "") << "no valid token, no one named";
      EXPECT_EQ(events[0].resource(), "");
      EXPECT_THAT(events[0].peer(), ::testing::StartsWith("ipv4:127.0.0.1:"));
    }
  }
  // Health checking stays open, for load balancers and orchestrators.
  EXPECT_TRUE(CallGeneric(anonymous, "/grpc.health.v1.Health/Check", {""}).status.ok());
}

TEST_F(RoleMatrixTest, EachRoleSucceedsInExactlyTheCallsAtOrBelowItOverGrpcAndEveryWriteIsAudited) {
  int calls = 0;
  for (const auto* method : EveryServedMethod()) {
    const v1::Role least = method->options().GetExtension(v1::access).role();
    for (v1::Role role : kRoles) {
      const std::optional<Call> call = CallOf(method);
      ASSERT_TRUE(call.has_value()) << method->full_name() << ": no case in this test";
      grpc::GenericStub stub(callers_[role].channel);
      const std::int64_t before = NewestAuditEvent();
      const GenericAnswer answer = CallGeneric(stub, GrpcPath(method), call->requests);
      ++calls;
      const std::string what = method->full_name() + " as " + v1::Role_Name(role);
      if (role < least) {
        EXPECT_EQ(answer.status.error_code(), grpc::StatusCode::PERMISSION_DENIED) << what;
        EXPECT_THAT(answer.status.error_message(), HasSubstr(v1::Role_Name(least))) << what;
        EXPECT_TRUE(answer.responses.empty()) << what;
      } else {
        EXPECT_TRUE(answer.status.ok())
            << what << ": " << answer.status.error_code() << " " << answer.status.error_message();
        EXPECT_FALSE(answer.responses.empty()) << what << " answered nothing";
        // Each answer is a message of the method's output type.
        for (const std::string& bytes : answer.responses) {
          std::unique_ptr<Message> response(google::protobuf::MessageFactory::generated_factory()
                                                ->GetPrototype(method->output_type())
                                                ->New());
          EXPECT_TRUE(response->ParseFromString(bytes)) << what;
        }
      }
      ExpectAudited(method, role, *call, before, role >= least, "gRPC");
    }
  }
  EXPECT_EQ(calls, 44 * 4);
}

TEST_F(RoleMatrixTest,
       EachRoleSucceedsInExactlyTheRoutesAtOrBelowItOverRestAndEveryWriteIsAudited) {
  int routes = 0;
  for (const auto* method : EveryServedMethod()) {
    const v1::Role least = method->options().GetExtension(v1::access).role();
    if (!method->options().HasExtension(google::api::http)) {
      // Requests that stream in have no REST form: only MonitorRun.
      EXPECT_TRUE(method->client_streaming() && method->name() == "MonitorRun")
          << method->full_name();
      continue;
    }
    ++routes;
    for (v1::Role role : kRoles) {
      const std::optional<Call> call = CallOf(method);
      ASSERT_TRUE(call.has_value() && call->rest.has_value())
          << method->full_name() << ": no REST case";
      const RestRequest& rest = *call->rest;
      httplib::Client& http = *callers_[role].http;
      const std::int64_t before = NewestAuditEvent();
      httplib::Result answer =
          rest.verb == "GET"    ? http.Get(rest.path.c_str())
          : rest.verb == "POST" ? http.Post(rest.path.c_str(), rest.body, rest.content_type.c_str())
                                : http.Delete(rest.path.c_str());
      const std::string what = rest.verb + " " + rest.path + " as " + v1::Role_Name(role);
      ASSERT_TRUE(answer) << what;
      if (role < least) {
        EXPECT_EQ(answer->status, 403) << what << ": " << answer->body;
        EXPECT_THAT(answer->body, HasSubstr("PERMISSION_DENIED")) << what;
        EXPECT_THAT(answer->body, HasSubstr(v1::Role_Name(least))) << what;
      } else {
        EXPECT_EQ(answer->status, 200) << what << ": " << answer->body.substr(0, 300);
        EXPECT_FALSE(answer->body.empty()) << what;
        // A streamed answer tells an error after its first line as a last line {"error":…}.
        if (method->server_streaming()) {
          EXPECT_THAT(answer->body, ::testing::Not(HasSubstr("\"error\""))) << what;
        }
      }
      ExpectAudited(method, role, *call, before, role >= least, "REST");
    }
  }
  EXPECT_EQ(routes, 43);
}

}  // namespace
}  // namespace insdiag::testing
