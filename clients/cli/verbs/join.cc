// insdiag join FILE... -o TEST.csv
// Joins the files of a multi-position test — static positions and turns
// recorded one after another, with unrecorded moves between them — into one
// bench run of segments (format version 2, docs/MULTI_POSITION.md). Each
// file becomes a segment, in the order given; the files must be of one unit
// at one site with one sample interval. The segments follow one another in
// time: each file's times are moved to start one interval after the
// previous file's end (benchrun::JoinBenchRunFiles).
#include <ostream>

#include "insdiag/benchrun/bench_run_csv.h"
#include "insdiag/benchrun/bench_run_join.h"
#include "verb.h"

namespace insdiag::cli {
namespace {

class JoinVerb final : public Verb {
 public:
  std::string Name() const override { return "join"; }
  std::string Summary() const override {
    return "Join the files of a multi-position test into one bench run of segments";
  }

  void DeclareOptions(OptionSink& options) override {
    options.Positionals("FILE", &files_, "Bench-run files, one per position or turn, in test order");
    options.Option("-o,--output", &output_, "The joined bench run (TEST.csv)");
  }

  int Run(std::ostream& out, std::ostream& err) override {
    if (files_.size() < 2 || output_.empty()) {
      err << "insdiag join: give two files or more and --output TEST.csv\n";
      return kExitUsage;
    }
    auto joined = benchrun::JoinBenchRunFiles({files_.begin(), files_.end()});
    if (!joined.ok()) {
      err << joined.status().message() << "\n";
      return kExitRefused;
    }
    if (absl::Status written = benchrun::WriteBenchRunFile(*joined, output_); !written.ok()) {
      err << written.message() << "\n";
      return kExitRefused;
    }
    out << output_ << ": " << joined->metadata.segment_starts.size() + 1 << " segments, "
        << joined->samples.size() << " samples\n";
    return kExitOk;
  }

 private:
  std::vector<std::string> files_;
  std::string output_;
};

}  // namespace

std::unique_ptr<Verb> MakeVerb_join() { return std::make_unique<JoinVerb>(); }

}  // namespace insdiag::cli
