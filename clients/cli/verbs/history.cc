// insdiag history UNIT [--parameter NAME]... [--confidence C] [--json]
// A unit's history on the server: its runs with their analyses, then per
// identified parameter the runs counted (n), the mean, the run-to-run
// repeatability with its confidence interval, a turn-on bias's
// turn-on-to-turn-on repeatability, and the trend per day ± its standard
// error with the p-value of a zero slope. --json prints the whole history
// (every run, every point). Takes [--server ADDR] [--token TOKEN].
#include <ostream>

#include "insdiag/client/unary.h"
#include "insdiag/v1/knowledge.grpc.pb.h"
#include "server_output.h"
#include "verb.h"

namespace insdiag::cli {
namespace {

// Every run of the history: the server pages them.
constexpr int kRunsPerPage = 1000;

class HistoryVerb final : public Verb {
 public:
  std::string Name() const override { return "history"; }
  std::string Summary() const override {
    return "A unit's runs and analyses over time, each parameter's repeatability and trend";
  }

  void DeclareOptions(OptionSink& options) override {
    options.Positionals("UNIT", &arguments_, "the unit (units/{serial} or the serial)");
    options.Option("--parameter", &parameter_, "only this parameter, e.g. gyro_turn_on_bias.x");
    options.Option("--confidence", &confidence_, "of the repeatability intervals (default 0.95)");
    options.Flag("--json", &json_, "Print the history as JSON");
    server_.Declare(options);
  }

  int Run(std::ostream& out, std::ostream& err) override {
    if (arguments_.size() != 1) return UsageError(err, Name(), "expected one UNIT");
    v1::GetUnitHistoryRequest request;
    request.set_unit(ResourceName("units", arguments_.front()));
    request.set_page_size(kRunsPerPage);
    if (!parameter_.empty()) request.add_parameters(parameter_);
    double confidence = 0.0;
    if (auto s = ParseDouble(confidence_, "--confidence", &confidence); !s.ok()) {
      return UsageError(err, Name(), std::string(s.message()));
    }
    request.set_confidence(confidence);
    auto stub = v1::KnowledgeService::NewStub(server_.Connect());
    v1::UnitHistory history;
    do {
      auto page = client::CallUnary<v1::UnitHistory>(
          [&](grpc::ClientContext* c, v1::UnitHistory* r) { return stub->GetUnitHistory(c, request, r); });
      if (!page.ok()) return RequestFailed(err, Name(), "get unit history", page.status());
      if (history.unit().empty()) {
        history = *page;
      } else {
        for (auto& r : *page->mutable_runs()) *history.add_runs() = std::move(r);
      }
      request.set_page_token(page->next_page_token());
    } while (!request.page_token().empty());
    history.clear_next_page_token();
    if (json_) return PrintJson(history, out, err);
    Print(history, out);
    return kExitOk;
  }

 private:
  static void Print(const v1::UnitHistory& h, std::ostream& out) {
    out << h.unit() << (h.unit_type().empty() ? "" : " (" + h.unit_type() + ")") << ": " << h.run_count()
        << " runs, " << h.analysed_run_count() << " analysed\n\n";
    Table runs({"run", "tested", "analyses", "counted analysis", "verdict"});
    for (const auto& r : h.runs()) {
      std::string counted, verdict;
      for (const auto& a : r.analyses()) {
        if (!a.counted()) continue;
        counted = a.analysis();
        verdict = v1::AnalysisReport::Verdict_Name(a.verdict());
      }
      runs.Add({r.run(), DateTime(r.test_time()), std::to_string(r.analyses_size()), counted, verdict});
    }
    runs.Print(out);
    out << "\n";
    const std::string level = Number(100.0 * h.confidence(), 3) + " %";
    Table table({"parameter", "unit", "n", "mean", "run-to-run sd", level + " interval", "turn-on sd",
                 "trend /day", "± se", "p"});
    for (const auto& p : h.parameters()) {
      const auto& s = p.statistics();
      const bool sd = s.count() >= 2;
      const auto& t = s.trend();
      table.Add({p.name(), p.unit(), std::to_string(s.count()), Number(s.mean()), sd ? Number(s.run_to_run_sd(), 3) : "",
                 sd ? Number(s.run_to_run_sd_low(), 3) + " – " + Number(s.run_to_run_sd_high(), 3) : "",
                 s.has_turn_on_to_turn_on_sd() ? Number(s.turn_on_to_turn_on_sd(), 3) : "",
                 t.fitted() ? Number(t.slope_per_day(), 3) : "", t.fitted() ? Number(t.slope_std_error_per_day(), 2) : "",
                 t.fitted() ? Number(t.p_value(), 2) + (t.excess_scatter() ? " *" : "") : ""});
    }
    table.Print(out);
    out << "\n* the scatter exceeds what the standard errors explain: the trend's error is scaled by the Birge ratio\n";
    for (const auto& note : h.notes()) out << "note: " << note << "\n";
  }

  std::vector<std::string> arguments_;
  std::string parameter_;
  std::string confidence_;
  bool json_ = false;
  ServerFlags server_;
};

}  // namespace

std::unique_ptr<Verb> MakeVerb_history() { return std::make_unique<HistoryVerb>(); }

}  // namespace insdiag::cli
