// insdiag report ANALYSIS [--json | --format text|html|pdf [-o FILE] [--diagnosis NAME]] [--server ADDR]
// Prints the report of a SUCCEEDED analysis (analyses/{id} or the id): the
// verdict, the fit per channel, identified parameters, the most significant
// missing effects, where the model fails. --format html|pdf writes the test
// report instead, the self-contained document the server sets
// (AnalysisService.GetTestReport), to FILE or standard output.
#include <fstream>
#include <ostream>

#include "insdiag/client/unary.h"
#include "insdiag/v1/analyses.grpc.pb.h"
#include "report_text.h"
#include "server_output.h"
#include "verb.h"

namespace insdiag::cli {
namespace {

void PrintReportText(const v1::Analysis& analysis, std::ostream& out) {
  const v1::AnalysisReport& r = analysis.report();
  out << analysis.name() << " of " << analysis.unit() << " (" << analysis.run() << "), "
      << DateTime(analysis.create_time()) << "\n"
      << "verdict " << v1::AnalysisReport::Verdict_Name(r.verdict()) << ", mean NIS " << Number(r.nis_mean());
  if (!r.model().effects().empty()) {
    out << ", model + ";
    for (int i = 0; i < r.model().effects_size(); ++i) out << (i > 0 ? ", " : "") << r.model().effects(i);
  }
  out << "\n";
  for (const std::string& line : r.plain_words()) out << "  " << line << "\n";
  if (r.channels_size() > 0) {
    out << "\n";
    Table channels({"channel", "rms", "unit", "fit", "NIS", "whiteness p"});
    for (const auto& c : r.channels()) {
      channels.Add({c.name(), Number(c.rms()), c.unit(), Percent(c.fit_percent() / 100.0), Number(c.nis_mean()),
                    Number(c.whiteness_p_value(), 2)});
    }
    channels.Print(out);
  }
  if (r.identified_size() > 0) {
    out << "\n";
    Table identified({"identified", "value", "± std error", "unit", "method", "observability"});
    for (const auto& p : r.identified()) {
      identified.Add({p.name(), Number(p.value()), Number(p.std_error(), 2), p.unit(),
                      v1::IdentifiedParameter::Method_Name(p.method()),
                      ObservabilityText(p.observability(), p.observability_note())});
    }
    identified.Print(out);
  }
  if (r.effect_candidates_size() > 0) {
    out << "\n";
    Table candidates({"missing effect", "estimate", "± std error", "unit", "Holm p"});
    int shown = 0;
    for (const auto& c : r.effect_candidates()) {
      if (shown++ == 10) break;
      candidates.Add({c.name(), Number(c.estimate()), Number(c.std_error(), 2), c.unit(), Number(c.p_value_holm(), 2)});
    }
    candidates.Print(out);
    if (r.effect_candidates_size() > 10) out << "(" << r.effect_candidates_size() - 10 << " more: --json)\n";
  }
  if (r.fault_intervals_size() > 0) {
    out << "\n";
    Table intervals({"fails on", "from [s]", "to [s]", "kind"});
    for (const auto& f : r.fault_intervals()) {
      intervals.Add({f.channel(), Number(f.start_s(), 6), Number(f.end_s(), 6), v1::FaultInterval::Kind_Name(f.kind())});
    }
    intervals.Print(out);
  }
  if (r.bench_motion_size() > 0) {
    out << "\n";
    Table moved({"bench moved", "from [s]", "to [s]", "scatter [σ]"});
    for (const auto& m : r.bench_motion()) {
      moved.Add({m.channel(), Number(m.start_s(), 6), Number(m.end_s(), 6), Number(m.statistic(), 3)});
    }
    moved.Print(out);
  }
  for (const auto& note : r.notes()) out << "note: " << note << "\n";
}

class ReportVerb final : public Verb {
 public:
  std::string Name() const override { return "report"; }
  std::string Summary() const override { return "Print the report of an analysis, or write its test report (HTML, PDF)"; }

  void DeclareOptions(OptionSink& options) override {
    options.Positional("ANALYSIS", &analysis_, "analyses/{id} or the id");
    options.Flag("--json", &json_, "Print the report as JSON (insdiag.v1.AnalysisReport)");
    options.Option("--format", &format_,
                   "text (the default), or the test report to file: html (self-contained) or pdf");
    options.Option("-o,--output", &output_, "Write the html or pdf test report to FILE (default: standard output)");
    options.Option("--diagnosis", &diagnosis_,
                   "The diagnosis the test report shows (diagnoses/{id}; default: the analysis's newest)");
    server_.Declare(options);
  }

  int Run(std::ostream& out, std::ostream& err) override {
    if (format_ != "text" && format_ != "html" && format_ != "pdf") {
      err << "insdiag report: --format is text, html or pdf, not '" << format_ << "'\n";
      return kExitUsage;
    }
    if (format_ == "text" && (!output_.empty() || !diagnosis_.empty())) {
      err << "insdiag report: --output and --diagnosis go with --format html or pdf\n";
      return kExitUsage;
    }
    if (format_ != "text") {
      if (json_) {
        err << "insdiag report: --json prints the report's JSON; it does not go with --format " << format_ << "\n";
        return kExitUsage;
      }
      return WriteTestReport(out, err);
    }
    v1::GetAnalysisRequest request;
    request.set_name(ResourceName("analyses", analysis_));
    auto stub = v1::AnalysisService::NewStub(server_.Connect());
    auto analysis = client::CallUnary<v1::Analysis>(
        [&](grpc::ClientContext* c, v1::Analysis* r) { return stub->GetAnalysis(c, request, r); });
    if (!analysis.ok()) return RequestFailed(err, Name(), "get analysis", analysis.status());
    if (analysis->state() != v1::Analysis::SUCCEEDED) {
      err << "insdiag report: " << analysis->name() << " is " << v1::Analysis::State_Name(analysis->state())
          << (analysis->state() == v1::Analysis::FAILED ? ": " + analysis->error().message() : "")
          << ": only a SUCCEEDED analysis has a report\n";
      return kExitRefused;
    }
    if (json_) return PrintJson(analysis->report(), out, err);
    PrintReportText(*analysis, out);
    return kExitOk;
  }

 private:
  int WriteTestReport(std::ostream& out, std::ostream& err) {
    v1::GetTestReportRequest request;
    request.set_name(ResourceName("analyses", analysis_));
    request.set_format(format_);
    if (!diagnosis_.empty()) request.set_diagnosis(ResourceName("diagnoses", diagnosis_));
    auto stub = v1::AnalysisService::NewStub(server_.Connect());
    auto document = client::CallUnary<google::api::HttpBody>(
        [&](grpc::ClientContext* c, google::api::HttpBody* r) { return stub->GetTestReport(c, request, r); });
    if (!document.ok()) return RequestFailed(err, Name(), "get the test report", document.status());
    if (output_.empty()) {
      out.write(document->data().data(), static_cast<std::streamsize>(document->data().size()));
      return kExitOk;
    }
    std::ofstream file(output_, std::ios::binary);
    file.write(document->data().data(), static_cast<std::streamsize>(document->data().size()));
    file.close();
    if (!file) {
      err << "insdiag report: cannot write " << output_ << "\n";
      return kExitRefused;
    }
    out << output_ << "\n";
    return kExitOk;
  }

  std::string analysis_;
  ServerFlags server_;
  bool json_ = false;
  std::string format_ = "text";
  std::string output_;
  std::string diagnosis_;
};

}  // namespace

std::unique_ptr<Verb> MakeVerb_report() { return std::make_unique<ReportVerb>(); }

}  // namespace insdiag::cli
