// insdiag analyze RUN.csv [--add EFFECT]... [--base REPORT.json] [--json] [--series OUT.csv]
// Runs the engine locally on a bench-run file, no server needed.
#include <absl/strings/numbers.h>
#include <absl/strings/str_format.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <ostream>
#include <sstream>

#include "insdiag/api/json.h"
#include "insdiag/api/report_codec.h"
#include "insdiag/api/unit_types.h"
#include "insdiag/benchrun/bench_run_csv.h"
#include "insdiag/engine/analysis.h"
#include "insdiag/engine/status_macros.h"
#include "report_text.h"
#include "verb.h"

namespace insdiag::cli {
namespace {

class AnalyzeVerb final : public Verb {
 public:
  std::string Name() const override { return "analyze"; }
  std::string Summary() const override {
    return "Compare the unit's error model with a bench run: fit, where it fails, missing effects";
  }

  void DeclareOptions(OptionSink& options) override {
    options.Positional("RUN.csv", &file_, "Bench-run file (shared/spec/bench-run-format.md)");
    options.Repeated("--add", &add_,
                     "Put a catalogue effect into the model: a term (gyro_scale_factor.z) or a family "
                     "(gyro_scale_factor), a fault at its onset (gyro_bias_step.x@1500), a warm-up at its time "
                     "constant (gyro_warm_up.x@516); repeatable");
    options.Repeated("--baseline", &baseline_,
                     "Start from a model with this effect (term or family) in it: identification and the "
                     "scan run on that model; repeatable");
    options.Option("--base", &base_,
                   "Start from the model an earlier analysis of the same run identified: its --json report. "
                   "Identification is not run again, so --add costs two filter passes");
    options.Flag("--discover", &discover_,
                 "Walk the loop: add the most significant missing effect, re-run, repeat until nothing is "
                 "significant; print the path");
    options.Flag("--json", &json_, "Print the report as JSON (insdiag.v1.AnalysisReport)");
    options.Option("--acf", &acf_, "Write each drift's autocorrelation, its band and the families' fits to CSV");
    options.Option("--allan", &allan_, "Write the Allan deviation curves with their confidence intervals and fits to CSV");
    options.Option("--series", &series_, "Write measured, predicted, residual and ±3σ per channel and epoch to CSV");
    options.Option("--unit-type", &unit_type_,
                   "Unit type whose nominal model completes a datasheet the run lacks (default: the run's "
                   "unit_type when insdiag knows it)");
    options.Option("--update-interval", &update_interval_,
                   "Seconds between filter updates (default 1; at least two samples)");
    options.Flag("--progress", &progress_, "Print each stage of the analysis with the seconds elapsed to stderr");
  }

  int Run(std::ostream& out, std::ostream& err) override {
    auto run = benchrun::ReadBenchRunFile(file_);
    if (!run.ok()) {
      err << run.status().message() << "\n";
      return kExitRefused;
    }
    engine::AnalysisRequest request;
    request.add_effects = add_;
    request.baseline_effects = baseline_;
    request.discover = discover_;
    if (discover_ && !add_.empty()) {
      err << "insdiag analyze: --discover chooses the effects itself; use --baseline to start from yours\n";
      return kExitUsage;
    }
    if (!base_.empty()) {
      auto base = ReadIdentifiedModel(base_);
      if (!base.ok()) {
        err << "insdiag analyze: --base " << base_ << ": " << base.status().message() << "\n";
        return kExitRefused;
      }
      request.identified_base = *std::move(base);
    }
    const std::string type = unit_type_.empty() ? run->metadata.unit_type : unit_type_;
    if (!type.empty()) {
      auto unit_type = api::BuiltinUnitType(type);
      if (unit_type.ok()) {
        auto nominal = api::BaseModelOf(*unit_type);
        if (nominal.ok()) request.nominal = *nominal;
      } else if (!unit_type_.empty()) {
        err << "insdiag analyze: " << unit_type.status().message() << "\n";
        return kExitUsage;
      }
    }
    engine::AnalysisOptions options;
    if (!absl::SimpleAtod(update_interval_, &options.filter.update_interval_s) ||
        !std::isfinite(options.filter.update_interval_s)) {
      err << "insdiag analyze: --update-interval: '" << update_interval_ << "' is not a number\n";
      return kExitUsage;
    }
    options.keep_series = !series_.empty();
    const auto started = std::chrono::steady_clock::now();
    if (progress_) {
      options.progress = [&err, started](double fraction, std::string_view stage) {
        const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - started;
        err << absl::StrFormat("%7.1f s  %3.0f %%  %s\n", elapsed.count(), 100.0 * fraction, stage)
            << std::flush;
      };
    }
    auto analysis = engine::Analyze(*std::move(run), request, options);
    if (!analysis.ok()) {
      err << "insdiag analyze: " << file_ << ": " << analysis.status().message() << "\n";
      return analysis.status().code() == absl::StatusCode::kInvalidArgument ? kExitUsage : kExitRefused;
    }
    if (!series_.empty()) {
      std::ofstream series(series_);
      WriteSeriesCsv(analysis->series, series);
      if (!series) {
        err << "insdiag analyze: cannot write " << series_ << "\n";
        return kExitRefused;
      }
    }
    auto write = [&](const std::string& path, auto writer) {
      if (path.empty()) return true;
      std::ofstream file(path);
      writer(analysis->report, file);
      if (!file) err << "insdiag analyze: cannot write " << path << "\n";
      return static_cast<bool>(file);
    };
    if (!write(acf_, WriteCorrelationCsv) || !write(allan_, WriteAllanCsv)) return kExitRefused;
    if (json_) {
      auto text = api::ToJson(api::ToProto(analysis->report, analysis->model), /*pretty=*/true);
      if (!text.ok()) {
        err << "insdiag analyze: " << text.status().message() << "\n";
        return kExitRefused;
      }
      out << *text << "\n";
    } else {
      PrintReport(analysis->report, out);
    }
    return kExitOk;
  }

 private:
  std::string file_;
  std::vector<std::string> add_;
  // The identified model of an `insdiag analyze --json` report.
  static absl::StatusOr<engine::IdentifiedModel> ReadIdentifiedModel(const std::string& path) {
    std::ifstream file(path);
    std::ostringstream text;
    if (!file || !(text << file.rdbuf())) return absl::NotFoundError("cannot read the file");
    v1::AnalysisReport report;
    INSDIAG_RETURN_IF_ERROR(api::FromJson(text.str(), &report));
    return api::IdentifiedModelOf(report);
  }

  std::string base_;
  std::vector<std::string> baseline_;
  bool discover_ = false;
  std::string acf_;
  std::string allan_;
  bool json_ = false;
  bool progress_ = false;
  std::string series_;
  std::string unit_type_;
  std::string update_interval_ = "1";
};

}  // namespace

std::unique_ptr<Verb> MakeVerb_analyze() { return std::make_unique<AnalyzeVerb>(); }

}  // namespace insdiag::cli
