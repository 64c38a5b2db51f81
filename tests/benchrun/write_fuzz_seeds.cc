// Writes the bench runs the tests are built on into a directory, as seeds of
// the bench-run reader's fuzzer (scripts/fuzz.sh): the reader tests' CSV
// fixture (LF and CRLF), the value the CSV describes and the server tests'
// synthetic run as the writer formats them, a run of segments.
// Usage: write_fuzz_seeds DIR
#include <filesystem>
#include <fstream>
#include <iostream>

#include "insdiag/benchrun/bench_run_csv.h"
#include "support/synthetic_run.h"
#include "test_runs.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: write_fuzz_seeds DIR\n";
    return 2;
  }
  namespace fs = std::filesystem;
  using insdiag::benchrun::FormatBenchRun;
  const fs::path dir = argv[1];
  fs::create_directories(dir);
  const auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name, std::ios::binary) << text;
  };
  const insdiag::benchrun::testing::CsvText csv(20);
  write("test-csv-fixture", csv.Text());
  write("test-csv-fixture-crlf", csv.Text("\r\n"));
  write("test-static-run-formatted", FormatBenchRun(insdiag::benchrun::testing::StaticRun(20)));
  insdiag::engine::BenchRun synthetic = insdiag::testing::SyntheticStaticRun(30, 50.0, 3);
  write("server-test-synthetic-run", FormatBenchRun(synthetic));
  synthetic.has_temperature = false;
  synthetic.metadata.format = "insdiag-bench-run/2";
  synthetic.metadata.segment_starts = {0, 15};
  write("server-test-synthetic-run-segments", FormatBenchRun(synthetic));
  return 0;
}
