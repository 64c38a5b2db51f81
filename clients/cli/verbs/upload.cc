// insdiag upload RUN.csv [--server ADDR] [--request-id ID]
// Reads the bench-run file, streams it to the server, prints the run's name.
#include <ostream>

#include "insdiag/benchrun/bench_run_csv.h"
#include "insdiag/client/run_client.h"
#include "server_output.h"
#include "verb.h"

namespace insdiag::cli {
namespace {

class UploadVerb final : public Verb {
 public:
  std::string Name() const override { return "upload"; }
  std::string Summary() const override { return "Upload a bench run to the server and print the run's name"; }

  void DeclareOptions(OptionSink& options) override {
    options.Positional("RUN.csv", &file_, "Bench-run file (shared/spec/bench-run-format.md)");
    server_.Declare(options);
    options.Option("--request-id", &request_id_,
                   "Idempotency key; uploading again with the same key returns the same run "
                   "(default: a new random key)");
  }

  int Run(std::ostream& out, std::ostream& err) override {
    // Refused files are named here, before anything is sent:
    // "RUN.csv:LINE:COLUMN: field: why".
    auto run = benchrun::ReadBenchRunFile(file_);
    if (!run.ok()) {
      err << run.status().message() << "\n";
      return kExitRefused;
    }
    auto stub = v1::RunService::NewStub(server_.Connect());
    client::UploadOptions options;
    options.request_id = request_id_.empty() ? client::NewRequestId() : request_id_;
    auto stored = client::UploadRun(*stub, *run, options);
    if (!stored.ok()) {
      err << "insdiag upload: " << server_.address << ": " << absl::StatusCodeToString(stored.status().code()) << ": "
          << stored.status().message() << "\n";
      return kExitRefused;
    }
    out << stored->name() << "\n";
    return kExitOk;
  }

 private:
  std::string file_;
  ServerFlags server_;
  std::string request_id_;
};

}  // namespace

std::unique_ptr<Verb> MakeVerb_upload() { return std::make_unique<UploadVerb>(); }

}  // namespace insdiag::cli
