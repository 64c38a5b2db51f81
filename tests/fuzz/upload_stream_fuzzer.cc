// The upload stream's checks (server/upload_assembler.h) on streams a fuzzer
// bends out of a valid one: the input's first bytes say how many samples,
// how big the chunks, which message to drop, repeat or move and where to
// splice in raw message bytes; the remaining 8-byte words overwrite sample
// values (NaN, infinities, huge and tiny numbers). Whatever arrives, the
// assembler refuses with a reason or returns a run of exactly the samples
// it was sent — never a crash.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "insdiag/api/run_codec.h"
#include "insdiag/server/upload_assembler.h"

namespace {

insdiag::engine::BenchRun ValidRun(int samples) {
  insdiag::engine::BenchRun run;
  run.metadata.format = "insdiag-bench-run/1";
  run.metadata.unit_serial = "FUZZ-1";
  run.metadata.site.latitude_rad = 0.8;
  run.metadata.site.longitude_rad = 0.1;
  run.metadata.site.height_m = 100.0;
  run.has_temperature = true;
  for (int k = 0; k < samples; ++k) {
    insdiag::engine::ImuSample s;
    s.t_s = 0.01 * k;
    s.acc_mps2.z() = -9.81;
    s.temp_degc = 25.0;
    run.samples.push_back(s);
  }
  return run;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 6) return 0;
  const int samples = 1 + data[0] % 64;
  const std::size_t chunk = 1 + data[1] % 16;
  const int drop = data[2], repeat = data[3], splice_at = data[4];
  const std::size_t splice_bytes = data[5] % 64;
  data += 6, size -= 6;

  insdiag::engine::BenchRun run = ValidRun(samples);
  // Overwrite sample values with the input's words, field by field.
  std::size_t word = 0;
  for (auto& s : run.samples) {
    double* fields[] = {&s.t_s, &s.gyro_rad_s.x(), &s.gyro_rad_s.y(), &s.gyro_rad_s.z(), &s.acc_mps2.x(),
                        &s.acc_mps2.y(), &s.acc_mps2.z(), &s.ref_rpy_rad.x(), &s.ref_rpy_rad.y(),
                        &s.ref_rpy_rad.z(), &s.temp_degc};
    for (double* f : fields) {
      if ((word + 1) * 8 > size - std::min(size, splice_bytes)) break;
      std::memcpy(f, data + splice_bytes + 8 * word++, 8);
    }
  }
  std::vector<insdiag::v1::UploadRunRequest> messages;
  insdiag::api::ForEachUploadRequest(run, "", chunk, [&](const insdiag::v1::UploadRunRequest& m) {
    messages.push_back(m);
    return true;
  });
  const int n = static_cast<int>(messages.size());
  if (drop < n) messages.erase(messages.begin() + drop);
  if (repeat < static_cast<int>(messages.size())) messages.push_back(messages[static_cast<std::size_t>(repeat)]);
  if (splice_bytes > 0 && splice_bytes <= size) {
    insdiag::v1::UploadRunRequest raw;
    if (raw.ParseFromArray(data, static_cast<int>(splice_bytes))) {
      const auto at = std::min<std::size_t>(static_cast<std::size_t>(splice_at), messages.size());
      messages.insert(messages.begin() + static_cast<std::ptrdiff_t>(at), raw);
    }
  }

  insdiag::server::UploadAssembler assembler(/*max_samples=*/1000);
  std::size_t sent = 0;
  for (const auto& m : messages) {
    sent += static_cast<std::size_t>(m.has_samples() ? m.samples().samples_size() : 0);
    if (!assembler.Accept(m).ok()) return 0;
  }
  auto done = assembler.Finish();
  if (done.ok() && done->run.samples.size() != sent) std::abort();
  if (!done.ok() && done.status().message().empty()) std::abort();
  return 0;
}
