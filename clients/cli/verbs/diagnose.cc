// insdiag diagnose RUN.csv [--server ADDR] [--json]
// Uploads the run, has the server analyse it (progress on stderr), asks for
// the diagnosis and prints it: the unit's modules ranked by fault
// probability with the evidence for each (shared/spec/cli-and-report.md).
#include <iomanip>
#include <ostream>

#include "insdiag/api/json.h"
#include "insdiag/benchrun/bench_run_csv.h"
#include "insdiag/client/run_client.h"
#include "insdiag/v1/analyses.grpc.pb.h"
#include "insdiag/v1/knowledge.grpc.pb.h"
#include "server_output.h"
#include "verb.h"

namespace insdiag::cli {
namespace {

class DiagnoseVerb final : public Verb {
 public:
  std::string Name() const override { return "diagnose"; }
  std::string Summary() const override {
    return "Upload a run, have the server analyse it and print the unit's probable faulty modules";
  }

  void DeclareOptions(OptionSink& options) override {
    options.Positional("RUN.csv", &file_, "Bench-run file (shared/spec/bench-run-format.md)");
    server_.Declare(options);
    options.Flag("--json", &json_, "Print the diagnosis as JSON (insdiag.v1.Diagnosis)");
    options.Repeated("--add", &add_, "Put a catalogue effect into the model (term or family); repeatable");
    options.Flag("--no-discover", &no_discover_,
                 "Diagnose from the first model's scan only; by default the server walks the loop (adds each "
                 "significant missing effect, re-runs) so the evidence is effects estimated in the model");
  }

  int Run(std::ostream& out, std::ostream& err) override {
    auto run = benchrun::ReadBenchRunFile(file_);
    if (!run.ok()) {
      err << run.status().message() << "\n";
      return kExitRefused;
    }
    const auto fail = [&](const std::string& what, const absl::Status& status) {
      err << "insdiag diagnose: " << what << ": " << absl::StatusCodeToString(status.code()) << ": "
          << status.message() << "\n";
      return kExitRefused;
    };
    auto channel = server_.Connect();
    auto runs = v1::RunService::NewStub(channel);
    client::UploadOptions upload;
    upload.request_id = client::NewRequestId();
    auto stored = client::UploadRun(*runs, *run, upload);
    if (!stored.ok()) return fail("upload", stored.status());
    err << "uploaded " << stored->name() << "\n";

    auto analyses = v1::AnalysisService::NewStub(channel);
    v1::Analysis analysis;
    {
      grpc::ClientContext context;
      v1::CreateAnalysisRequest request;
      request.mutable_analysis()->set_run(stored->name());
      for (const auto& e : add_) request.mutable_analysis()->mutable_model()->add_effects(e);
      request.mutable_analysis()->set_discover(!no_discover_);
      request.set_request_id(client::NewRequestId());
      if (auto s = analyses->CreateAnalysis(&context, request, &analysis); !s.ok()) {
        return fail("create analysis", client::FromGrpc(s));
      }
    }
    {
      grpc::ClientContext context;
      v1::WatchAnalysisRequest request;
      request.set_name(analysis.name());
      auto reader = analyses->WatchAnalysis(&context, request);
      v1::Analysis update;
      while (reader->Read(&update)) {
        analysis = update;
        err << "\r" << analysis.name() << " " << v1::Analysis::State_Name(analysis.state()) << " "
            << std::fixed << std::setprecision(0) << 100.0 * analysis.progress().fraction() << "% "
            << analysis.progress().stage() << "\033[K" << std::flush;
      }
      err << "\n";
      if (auto s = reader->Finish(); !s.ok()) return fail("watch analysis", client::FromGrpc(s));
    }
    if (analysis.state() != v1::Analysis::SUCCEEDED) {
      err << "insdiag diagnose: " << analysis.name() << " " << v1::Analysis::State_Name(analysis.state()) << ": "
          << analysis.error().message() << "\n";
      return kExitRefused;
    }
    auto knowledge = v1::KnowledgeService::NewStub(channel);
    v1::Diagnosis diagnosis;
    {
      grpc::ClientContext context;
      v1::CreateDiagnosisRequest request;
      request.set_analysis(analysis.name());
      if (auto s = knowledge->CreateDiagnosis(&context, request, &diagnosis); !s.ok()) {
        return fail("diagnose", client::FromGrpc(s));
      }
    }
    if (json_) {
      auto text = api::ToJson(diagnosis, /*pretty=*/true);
      if (!text.ok()) return fail("print", text.status());
      out << *text << "\n";
      return kExitOk;
    }
    out << diagnosis.name() << " of " << diagnosis.analysis() << " (" << diagnosis.unit() << ", verdict "
        << v1::AnalysisReport::Verdict_Name(analysis.report().verdict()) << ")\n";
    PrintDiagnosisText(diagnosis, out);
    return kExitOk;
  }

 private:
  std::string file_;
  ServerFlags server_;
  bool json_ = false;
  bool no_discover_ = false;
  std::vector<std::string> add_;
};

}  // namespace

std::unique_ptr<Verb> MakeVerb_diagnose() { return std::make_unique<DiagnoseVerb>(); }

}  // namespace insdiag::cli
