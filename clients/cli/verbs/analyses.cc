// insdiag analyses [--run RUN] [--unit SERIAL] [--page-size N] [--page-token T] [--json] [--server ADDR]
// Lists the server's analyses, newest first: state, verdict, unit, run.
#include <ostream>

#include "insdiag/client/unary.h"
#include "insdiag/v1/analyses.grpc.pb.h"
#include "server_output.h"
#include "verb.h"

namespace insdiag::cli {
namespace {

class AnalysesVerb final : public Verb {
 public:
  std::string Name() const override { return "analyses"; }
  std::string Summary() const override { return "List analyses on the server, newest first"; }

  void DeclareOptions(OptionSink& options) override {
    options.Option("--run", &run_, "Only analyses of this run (runs/{run} or its id)");
    options.Option("--unit", &unit_, "Only analyses of this unit (units/{serial} or the serial)");
    options.Option("--page-size", &page_size_, "Analyses per page (default 50, at most 1000)");
    options.Option("--page-token", &page_token_, "The next page, as printed after the previous one");
    options.Flag("--json", &json_, "Print insdiag.v1.ListAnalysesResponse as JSON");
    server_.Declare(options);
  }

  int Run(std::ostream& out, std::ostream& err) override {
    v1::ListAnalysesRequest request;
    int page_size = 0;
    if (auto s = ParseInt(page_size_, "--page-size", &page_size); !s.ok()) return UsageError(err, Name(), std::string(s.message()));
    request.set_page_size(page_size);
    request.set_page_token(page_token_);
    request.set_run(ResourceName("runs", run_));
    request.set_unit(ResourceName("units", unit_));
    auto stub = v1::AnalysisService::NewStub(server_.Connect());
    auto response = client::CallUnary<v1::ListAnalysesResponse>(
        [&](grpc::ClientContext* c, v1::ListAnalysesResponse* r) { return stub->ListAnalyses(c, request, r); });
    if (!response.ok()) return RequestFailed(err, Name(), "list analyses", response.status());
    if (json_) return PrintJson(*response, out, err);
    Table table({"analysis", "unit", "state", "created", "run"});
    for (const auto& a : response->analyses()) {
      table.Add({a.name(), a.unit(), v1::Analysis::State_Name(a.state()), DateTime(a.create_time()), a.run()});
    }
    table.Print(out);
    if (!response->next_page_token().empty()) out << "next page: --page-token " << response->next_page_token() << "\n";
    return kExitOk;
  }

 private:
  std::string run_, unit_, page_size_, page_token_;
  ServerFlags server_;
  bool json_ = false;
};

}  // namespace

std::unique_ptr<Verb> MakeVerb_analyses() { return std::make_unique<AnalysesVerb>(); }

}  // namespace insdiag::cli
