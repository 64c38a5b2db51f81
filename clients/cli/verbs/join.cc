// insdiag join FILE... -o TEST.csv
// Joins the files of a multi-position test — static positions and turns
// recorded one after another, with unrecorded moves between them — into one
// bench run of segments (format version 2, docs/MULTI_POSITION.md). Each
// file becomes a segment, in the order given; the files must be of one unit
// at one site with one sample interval. The segments follow one another in
// time: each file's times are moved to start one interval after the
// previous file's end.
#include <cmath>
#include <ostream>

#include "insdiag/benchrun/bench_run_csv.h"
#include "verb.h"

namespace insdiag::cli {
namespace {

// Sample intervals of the files agree to this fraction.
constexpr double kIntervalRelativeTolerance = 1e-6;

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
    engine::BenchRun joined;
    for (const std::string& file : files_) {
      auto run = benchrun::ReadBenchRunFile(file);
      if (!run.ok()) {
        err << run.status().message() << "\n";
        return kExitRefused;
      }
      if (std::string why = Append(*run, joined); !why.empty()) {
        err << file << ": " << why << "\n";
        return kExitRefused;
      }
    }
    joined.metadata.format = std::string(benchrun::kFormatV2);
    std::string sources;
    for (const std::string& f : files_) sources += (sources.empty() ? "" : " ") + f;
    joined.metadata.extra.emplace_back("joined_from", sources);
    if (absl::Status written = benchrun::WriteBenchRunFile(joined, output_); !written.ok()) {
      err << written.message() << "\n";
      return kExitRefused;
    }
    out << output_ << ": " << files_.size() << " segments, " << joined.samples.size() << " samples\n";
    return kExitOk;
  }

 private:
  // Appends `run` as the next segment(s); what makes it not fit, if anything.
  static std::string Append(const engine::BenchRun& run, engine::BenchRun& joined) {
    const double dt = run.NominalIntervalS();
    if (joined.samples.empty()) {
      joined.metadata = run.metadata;
      joined.metadata.segment_starts.clear();  // taken below with the file's samples
      joined.has_temperature = run.has_temperature;
    } else {
      const engine::BenchRunMetadata& m = joined.metadata;
      if (run.metadata.unit_serial != m.unit_serial) return "unit_serial: another unit (" + run.metadata.unit_serial + ")";
      if (run.metadata.site.latitude_rad != m.site.latitude_rad || run.metadata.site.longitude_rad != m.site.longitude_rad ||
          run.metadata.site.height_m != m.site.height_m) {
        return "site_latitude_deg: another site";
      }
      if (run.has_temperature != joined.has_temperature) return "temp: some files have temperature and some not";
      const double joined_dt = joined.NominalIntervalS();
      if (std::abs(dt - joined_dt) > kIntervalRelativeTolerance * joined_dt) return "t: another sample interval";
      joined.metadata.segment_starts.push_back(joined.samples.size());
    }
    const double shift = (joined.samples.empty() ? 0.0 : joined.samples.back().t_s) + dt - run.samples.front().t_s;
    const std::size_t offset = joined.samples.size();
    for (engine::ImuSample s : run.samples) {
      s.t_s += shift;
      joined.samples.push_back(s);
    }
    for (std::size_t start : run.metadata.segment_starts) joined.metadata.segment_starts.push_back(offset + start);
    return {};
  }

  std::vector<std::string> files_;
  std::string output_;
};

}  // namespace

std::unique_ptr<Verb> MakeVerb_join() { return std::make_unique<JoinVerb>(); }

}  // namespace insdiag::cli
