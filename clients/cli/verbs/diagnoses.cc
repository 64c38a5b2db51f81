// insdiag diagnoses [list] [--unit SERIAL] [--analysis ANALYSIS]
// insdiag diagnoses get DIAGNOSIS
// insdiag diagnoses create ANALYSIS
// insdiag diagnoses resolve DIAGNOSIS --module ROLE (--confirmed --mode MODE | --rejected)
//                           [--repair-action TEXT] [--notes TEXT]
// Diagnoses on the server: list them (newest first), show one, diagnose a
// SUCCEEDED analysis, or resolve one — confirming a failure mode writes a
// confirmed failure record, rejecting writes a no-fault-found record.
// All take [--json] [--server ADDR].
#include <ostream>

#include "insdiag/client/unary.h"
#include "insdiag/v1/knowledge.grpc.pb.h"
#include "server_output.h"
#include "verb.h"

namespace insdiag::cli {
namespace {

class DiagnosesVerb final : public Verb {
 public:
  std::string Name() const override { return "diagnoses"; }
  std::string Summary() const override {
    return "List, show, create or resolve (confirm / reject) diagnoses on the server";
  }

  void DeclareOptions(OptionSink& options) override {
    options.Positionals("ACTION", &arguments_,
                        "list (default) | get DIAGNOSIS | create ANALYSIS | resolve DIAGNOSIS");
    options.Option("--unit", &unit_, "list: only this unit's diagnoses (units/{serial} or the serial)");
    options.Option("--analysis", &analysis_, "list: only this analysis's diagnoses");
    options.Option("--page-size", &page_size_, "list: diagnoses per page (default 50, at most 1000)");
    options.Option("--page-token", &page_token_, "list: the next page");
    options.Option("--module", &module_, "resolve: the module found faulty or suspected, e.g. gyro.x");
    options.Option("--mode", &mode_, "resolve: the failure mode found (failureModes/{id} or the id)");
    options.Flag("--confirmed", &confirmed_, "resolve: the failure was confirmed on the bench");
    options.Flag("--rejected", &rejected_, "resolve: no fault found on the suspected module");
    options.Option("--repair-action", &repair_action_, "resolve: e.g. \"module replaced\"");
    options.Option("--notes", &notes_, "resolve: free text for the failure record");
    options.Flag("--json", &json_, "Print the response as JSON");
    server_.Declare(options);
  }

  int Run(std::ostream& out, std::ostream& err) override {
    const std::string action = arguments_.empty() ? "list" : arguments_.front();
    const std::size_t operands = arguments_.empty() ? 0 : arguments_.size() - 1;
    stub_ = v1::KnowledgeService::NewStub(server_.Connect());
    if (action == "list" && operands == 0) return List(out, err);
    if (action == "get" && operands == 1) return Get(arguments_[1], out, err);
    if (action == "create" && operands == 1) return Create(arguments_[1], out, err);
    if (action == "resolve" && operands == 1) return Resolve(arguments_[1], out, err);
    return UsageError(err, Name(),
                      "expected: list | get DIAGNOSIS | create ANALYSIS | resolve DIAGNOSIS --module ROLE "
                      "(--confirmed --mode MODE | --rejected)");
  }

 private:
  int Show(const v1::Diagnosis& d, std::ostream& out, std::ostream& err) {
    if (json_) return PrintJson(d, out, err);
    out << d.name() << " of " << d.analysis() << " (" << d.unit() << ", " << DateTime(d.create_time()) << ")\n";
    PrintDiagnosisText(d, out);
    return kExitOk;
  }

  int List(std::ostream& out, std::ostream& err) {
    v1::ListDiagnosesRequest request;
    int page_size = 0;
    if (auto s = ParseInt(page_size_, "--page-size", &page_size); !s.ok()) return UsageError(err, Name(), std::string(s.message()));
    request.set_page_size(page_size);
    request.set_page_token(page_token_);
    request.set_unit(ResourceName("units", unit_));
    request.set_analysis(ResourceName("analyses", analysis_));
    auto response = client::CallUnary<v1::ListDiagnosesResponse>(
        [&](grpc::ClientContext* c, v1::ListDiagnosesResponse* r) { return stub_->ListDiagnoses(c, request, r); });
    if (!response.ok()) return RequestFailed(err, Name(), "list diagnoses", response.status());
    if (json_) return PrintJson(*response, out, err);
    Table table({"diagnosis", "unit", "created", "top module", "failure mode", "p", "resolved"});
    for (const auto& d : response->diagnoses()) {
      const v1::Candidate* top = nullptr;
      for (const auto& c : d.candidates()) {
        if (c.module() != "healthy") {
          top = &c;
          break;
        }
      }
      table.Add({d.name(), d.unit(), DateTime(d.create_time()), top ? top->module() : "",
                 top ? top->failure_mode() : "", top ? Number(top->probability(), 3) : "",
                 d.failure_record().empty() ? "" : (d.confirmed() ? "confirmed" : "rejected")});
    }
    table.Print(out);
    if (!response->next_page_token().empty()) out << "next page: --page-token " << response->next_page_token() << "\n";
    return kExitOk;
  }

  int Get(const std::string& name, std::ostream& out, std::ostream& err) {
    v1::GetDiagnosisRequest request;
    request.set_name(ResourceName("diagnoses", name));
    auto d = client::CallUnary<v1::Diagnosis>(
        [&](grpc::ClientContext* c, v1::Diagnosis* r) { return stub_->GetDiagnosis(c, request, r); });
    if (!d.ok()) return RequestFailed(err, Name(), "get diagnosis", d.status());
    return Show(*d, out, err);
  }

  int Create(const std::string& analysis, std::ostream& out, std::ostream& err) {
    v1::CreateDiagnosisRequest request;
    request.set_analysis(ResourceName("analyses", analysis));
    auto d = client::CallUnary<v1::Diagnosis>(
        [&](grpc::ClientContext* c, v1::Diagnosis* r) { return stub_->CreateDiagnosis(c, request, r); });
    if (!d.ok()) return RequestFailed(err, Name(), "create diagnosis", d.status());
    return Show(*d, out, err);
  }

  int Resolve(const std::string& name, std::ostream& out, std::ostream& err) {
    if (confirmed_ == rejected_) return UsageError(err, Name(), "resolve: give exactly one of --confirmed and --rejected");
    if (module_.empty()) return UsageError(err, Name(), "resolve: --module is required");
    if (confirmed_ && mode_.empty()) return UsageError(err, Name(), "resolve --confirmed: --mode is required");
    v1::ResolveDiagnosisRequest request;
    request.set_name(ResourceName("diagnoses", name));
    request.set_module(module_);
    request.set_failure_mode(ResourceName("failureModes", mode_));
    request.set_confirmed(confirmed_);
    request.set_repair_action(repair_action_);
    request.set_notes(notes_);
    auto d = client::CallUnary<v1::Diagnosis>(
        [&](grpc::ClientContext* c, v1::Diagnosis* r) { return stub_->ResolveDiagnosis(c, request, r); });
    if (!d.ok()) return RequestFailed(err, Name(), "resolve diagnosis", d.status());
    return Show(*d, out, err);
  }

  std::vector<std::string> arguments_;
  std::string unit_, analysis_, page_size_, page_token_, module_, mode_, repair_action_, notes_;
  bool confirmed_ = false, rejected_ = false, json_ = false;
  ServerFlags server_;
  std::unique_ptr<v1::KnowledgeService::Stub> stub_;
};

}  // namespace

std::unique_ptr<Verb> MakeVerb_diagnoses() { return std::make_unique<DiagnosesVerb>(); }

}  // namespace insdiag::cli
