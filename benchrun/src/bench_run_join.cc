#include "insdiag/benchrun/bench_run_join.h"

#include <cmath>
#include <string>

#include "insdiag/benchrun/bench_run_csv.h"

namespace insdiag::benchrun {
namespace {

// Sample intervals of the files agree to this fraction.
constexpr double kIntervalRelativeTolerance = 1e-6;

// Appends `run` as the next segment(s); what makes it not fit, if anything.
std::string Append(const engine::BenchRun& run, engine::BenchRun& joined) {
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

}  // namespace

absl::StatusOr<engine::BenchRun> JoinBenchRunFiles(const std::vector<std::filesystem::path>& files) {
  engine::BenchRun joined;
  std::string sources;
  for (const std::filesystem::path& file : files) {
    auto run = ReadBenchRunFile(file);
    if (!run.ok()) return run.status();
    if (std::string why = Append(*run, joined); !why.empty()) {
      return absl::InvalidArgumentError(file.string() + ": " + why);
    }
    if (!sources.empty()) sources += ' ';
    sources += file.string();
  }
  joined.metadata.format = std::string(kFormatV2);
  joined.metadata.extra.emplace_back("joined_from", sources);
  return joined;
}

}  // namespace insdiag::benchrun
