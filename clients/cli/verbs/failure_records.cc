// insdiag failure-records [list] [--unit SERIAL] [--module UNIT/ROLE] [--mode MODE]
// insdiag failure-records create --module UNIT/ROLE --hours H
//                                (--confirmed --mode MODE | --no-fault-found | --censored)
//                                [--analysis ANALYSIS] [--repair-action TEXT] [--notes TEXT]
// insdiag failure-records correct failureRecords/{record} --reason TEXT --hours H
//                                 (--confirmed --mode MODE | --no-fault-found | --censored) [...]
// insdiag failure-records history failureRecords/{record}
// The refusals database: list records (newest first), write one, correct
// one (its previous version is kept) or show what its corrections replaced.
// A module is units/{serial}/modules/{role}, or SERIAL/ROLE for short.
// All take [--json] [--server ADDR].
#include <ostream>

#include "insdiag/api/resource_names.h"
#include "insdiag/client/unary.h"
#include "insdiag/v1/knowledge.grpc.pb.h"
#include "server_output.h"
#include "verb.h"

namespace insdiag::cli {
namespace {

// units/{serial}/modules/{role} from itself or "SERIAL/ROLE"; anything else
// goes to the server as given, to be refused there.
std::string ModuleNameOf(const std::string& text) {
  if (text.empty() || text.starts_with(api::ResourceName(api::kUnits, ""))) return text;
  const auto slash = text.find('/');
  if (slash == std::string::npos) return text;
  return api::ModuleName(text.substr(0, slash), text.substr(slash + 1));
}

class FailureRecordsVerb final : public Verb {
 public:
  std::string Name() const override { return "failure-records"; }
  std::string Summary() const override {
    return "List or write failure records (confirmed failures, no fault found, suspensions)";
  }

  void DeclareOptions(OptionSink& options) override {
    options.Positionals("ACTION", &arguments_, "list (default) | create | correct RECORD | history RECORD");
    options.Option("--reason", &reason_, "correct: why the record was wrong (kept with the replaced version)");
    options.Option("--unit", &unit_, "list: only this unit's records");
    options.Option("--module", &module_, "the module: units/{serial}/modules/{role} or SERIAL/ROLE");
    options.Option("--mode", &mode_, "the failure mode (failureModes/{id} or the id)");
    options.Option("--page-size", &page_size_, "list: records per page (default 50, at most 1000)");
    options.Option("--page-token", &page_token_, "list: the next page");
    options.Option("--hours", &hours_, "create: the unit's operating hours when the failure was detected");
    options.Option("--analysis", &analysis_, "create: the analysis that found it");
    options.Flag("--confirmed", &confirmed_, "create: a failure confirmed on the bench (needs --mode)");
    options.Flag("--no-fault-found", &no_fault_found_, "create: the suspected module showed no fault");
    options.Flag("--censored", &censored_, "create: the unit was withdrawn without failing (a suspension)");
    options.Option("--repair-action", &repair_action_, "create: e.g. \"module replaced\"");
    options.Option("--notes", &notes_, "create: free text");
    options.Flag("--json", &json_, "Print the response as JSON");
    server_.Declare(options);
  }

  int Run(std::ostream& out, std::ostream& err) override {
    const std::string action = arguments_.empty() ? "list" : arguments_.front();
    const bool names_record = action == "correct" || action == "history";
    const std::size_t expected_arguments = arguments_.empty() ? 0 : names_record ? 2 : 1;
    if ((action != "list" && action != "create" && !names_record) || arguments_.size() != expected_arguments) {
      return UsageError(err, Name(), "expected: list | create | correct failureRecords/{record} | history failureRecords/{record}");
    }
    stub_ = v1::KnowledgeService::NewStub(server_.Connect());
    if (action == "correct") return Correct(ResourceName("failureRecords", arguments_[1]), out, err);
    if (action == "history") return History(ResourceName("failureRecords", arguments_[1]), out, err);
    return action == "list" ? List(out, err) : Create(out, err);
  }

 private:
  int List(std::ostream& out, std::ostream& err) {
    v1::ListFailureRecordsRequest request;
    int page_size = 0;
    if (auto s = ParseInt(page_size_, "--page-size", &page_size); !s.ok()) return UsageError(err, Name(), std::string(s.message()));
    request.set_page_size(page_size);
    request.set_page_token(page_token_);
    request.set_unit(ResourceName("units", unit_));
    request.set_module(ModuleNameOf(module_));
    request.set_failure_mode(ResourceName("failureModes", mode_));
    auto response = client::CallUnary<v1::ListFailureRecordsResponse>(
        [&](grpc::ClientContext* c, v1::ListFailureRecordsResponse* r) { return stub_->ListFailureRecords(c, request, r); });
    if (!response.ok()) return RequestFailed(err, Name(), "list failure records", response.status());
    if (json_) return PrintJson(*response, out, err);
    Table table({"detected", "module", "kind", "failure mode", "hours", "repair"});
    for (const auto& f : response->failure_records()) {
      const char* kind = f.confirmed() ? "confirmed" : f.no_fault_found() ? "no fault found" : f.censored() ? "censored" : "reported";
      table.Add({DateTime(f.detected_time()), f.module(), kind, f.failure_mode(), Number(f.operating_hours(), 6),
                 f.repair_action()});
    }
    table.Print(out);
    if (!response->next_page_token().empty()) out << "next page: --page-token " << response->next_page_token() << "\n";
    return kExitOk;
  }

  // The facts that create and correct take from the flags; false after a usage error.
  bool Facts(const std::string& action, v1::FailureRecord* f, std::ostream& err) {
    if (static_cast<int>(confirmed_) + static_cast<int>(no_fault_found_) + static_cast<int>(censored_) != 1) {
      UsageError(err, Name(), action + ": give exactly one of --confirmed, --no-fault-found, --censored");
      return false;
    }
    if (confirmed_ && mode_.empty()) {
      UsageError(err, Name(), action + " --confirmed: --mode is required");
      return false;
    }
    double hours = 0;
    if (auto s = ParseDouble(hours_, "--hours", &hours); !s.ok()) {
      UsageError(err, Name(), std::string(s.message()));
      return false;
    }
    f->set_failure_mode(ResourceName("failureModes", mode_));
    f->set_operating_hours(hours);
    f->set_confirmed(confirmed_);
    f->set_no_fault_found(no_fault_found_);
    f->set_censored(censored_);
    f->set_repaired(confirmed_ && !repair_action_.empty());
    f->set_repair_action(repair_action_);
    f->set_notes(notes_);
    return true;
  }

  int Correct(const std::string& name, std::ostream& out, std::ostream& err) {
    if (reason_.empty()) return UsageError(err, Name(), "correct: --reason is required");
    v1::CorrectFailureRecordRequest request;
    request.set_name(name);
    request.set_reason(reason_);
    if (!Facts("correct", request.mutable_failure_record(), err)) return kExitUsage;
    auto record = client::CallUnary<v1::FailureRecord>(
        [&](grpc::ClientContext* c, v1::FailureRecord* r) { return stub_->CorrectFailureRecord(c, request, r); });
    if (!record.ok()) return RequestFailed(err, Name(), "correct " + name, record.status());
    if (json_) return PrintJson(*record, out, err);
    out << record->name() << " revision " << record->revision() << "\n";
    return kExitOk;
  }

  int History(const std::string& name, std::ostream& out, std::ostream& err) {
    v1::ListFailureRecordRevisionsRequest request;
    request.set_name(name);
    auto response = client::CallUnary<v1::ListFailureRecordRevisionsResponse>(
        [&](grpc::ClientContext* c, v1::ListFailureRecordRevisionsResponse* r) {
          return stub_->ListFailureRecordRevisions(c, request, r);
        });
    if (!response.ok()) return RequestFailed(err, Name(), "history of " + name, response.status());
    if (json_) return PrintJson(*response, out, err);
    Table table({"revision", "failure mode", "confirmed", "hours", "superseded", "reason"});
    for (const auto& v : response->revisions()) {
      const auto& f = v.failure_record();
      table.Add({std::to_string(f.revision()), f.failure_mode(), f.confirmed() ? "yes" : "no",
                 Number(f.operating_hours(), 6), DateTime(v.superseded_time()), v.reason()});
    }
    table.Print(out);
    return kExitOk;
  }

  int Create(std::ostream& out, std::ostream& err) {
    if (module_.empty()) return UsageError(err, Name(), "create: --module is required");
    v1::CreateFailureRecordRequest request;
    v1::FailureRecord* f = request.mutable_failure_record();
    if (!Facts("create", f, err)) return kExitUsage;
    f->set_module(ModuleNameOf(module_));
    f->set_analysis(ResourceName("analyses", analysis_));
    auto record = client::CallUnary<v1::FailureRecord>(
        [&](grpc::ClientContext* c, v1::FailureRecord* r) { return stub_->CreateFailureRecord(c, request, r); });
    if (!record.ok()) return RequestFailed(err, Name(), "create failure record", record.status());
    if (json_) return PrintJson(*record, out, err);
    out << record->name() << "\n";
    return kExitOk;
  }

  std::vector<std::string> arguments_;
  std::string unit_, module_, mode_, page_size_, page_token_, hours_, analysis_, repair_action_, notes_, reason_;
  bool confirmed_ = false, no_fault_found_ = false, censored_ = false, json_ = false;
  ServerFlags server_;
  std::unique_ptr<v1::KnowledgeService::Stub> stub_;
};

}  // namespace

std::unique_ptr<Verb> MakeVerb_failure_records() { return std::make_unique<FailureRecordsVerb>(); }

}  // namespace insdiag::cli
