// The bench-run CSV reader on arbitrary text: it refuses or accepts, never
// crashes, and what it accepts it writes back to text that reads back the
// same (bench_run_csv.h: ParseBenchRun(FormatBenchRun(run)) == run).
#include <cstdint>
#include <cstdio>
#include <string>
#include <cstdlib>
#include <string_view>

#include "insdiag/benchrun/bench_run_csv.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto run = insdiag::benchrun::ParseBenchRun(text, "fuzz.csv");
  if (!run.ok()) {
    if (run.status().message().empty()) std::abort();  // every refusal says why
    return 0;
  }
  const std::string written = insdiag::benchrun::FormatBenchRun(*run);
  auto again = insdiag::benchrun::ParseBenchRun(written, "written.csv");
  if (!again.ok()) {
    std::fprintf(stderr, "written text refused: %s\n---\n%s---\n", std::string(again.status().message()).c_str(),
                 written.c_str());
    std::abort();
  }
  if (const std::string rewritten = insdiag::benchrun::FormatBenchRun(*again); rewritten != written) {
    std::fprintf(stderr, "written:\n%s---\nread back and written again:\n%s---\n", written.c_str(), rewritten.c_str());
    std::abort();
  }
  return 0;
}
