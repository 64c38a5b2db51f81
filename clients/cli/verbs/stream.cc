// insdiag stream [SOURCE] [--follow] [--listen PORT] [--planned-duration S]
//                [--stop-when-faulty] [--json] [--server ADDR]
// Feeds a test to the server as the bench writes it (LiveRunService.MonitorRun,
// docs/LIVE.md): bench-run CSV lines from stdin ("-" or no SOURCE), from a
// file that is still growing (--follow: read on at its end until it has been
// idle for --idle-timeout), or from the first client of a TCP port on
// loopback (--listen). Prints the monitor's verdict, its tests and each fault
// interval as they happen; when the source ends (or at the first FAULTY
// verdict with --stop-when-faulty) the test is stored and analysed, and the
// run's and the analysis's names are printed.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>
#include <fcntl.h>

#include <absl/strings/numbers.h>
#include <absl/strings/str_format.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <limits>
#include <cmath>
#include <cstring>
#include <mutex>
#include <ostream>
#include <set>
#include <string>
#include <thread>

#include "insdiag/api/json.h"
#include "insdiag/api/run_codec.h"
#include "insdiag/benchrun/bench_run_csv.h"
#include "insdiag/client/run_client.h"
#include "insdiag/v1/live.grpc.pb.h"
#include "server_output.h"
#include "verb.h"

namespace insdiag::cli {
namespace {

using Clock = std::chrono::steady_clock;

// Lines from a file descriptor; with `follow`, its end is waited on until it
// has been idle for `idle_timeout`.
class LineSource {
 public:
  LineSource(int fd, bool follow, std::chrono::milliseconds idle_timeout)
      : fd_(fd), follow_(follow), idle_timeout_(idle_timeout) {}

  // False at the end of the source (or when `stop` is set between reads).
  bool Next(std::string& line, const std::atomic<bool>& stop) {
    auto idle_since = Clock::now();
    while (true) {
      if (const auto end = buffer_.find('\n', scanned_); end != std::string::npos) {
        line.assign(buffer_, 0, end);
        buffer_.erase(0, end + 1);
        scanned_ = 0;
        return true;
      }
      scanned_ = buffer_.size();
      if (stop.load()) return false;
      char chunk[1 << 14];
      const ssize_t got = ::read(fd_, chunk, sizeof chunk);
      if (got > 0) {
        buffer_.append(chunk, static_cast<size_t>(got));
        idle_since = Clock::now();
        continue;
      }
      if (got < 0 && errno == EINTR) continue;
      if (got == 0 && follow_ && Clock::now() - idle_since < idle_timeout_) {
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
        continue;
      }
      // The end: a last line without its break still counts.
      if (buffer_.empty()) return false;
      line.swap(buffer_);
      buffer_.clear();
      scanned_ = 0;
      return true;
    }
  }

 private:
  int fd_;
  bool follow_;
  std::chrono::milliseconds idle_timeout_;
  std::string buffer_;
  size_t scanned_ = 0;
};

// The first client of 127.0.0.1:port; -1 with `error` set on failure.
int AcceptOneClient(int port, std::string& error) {
  const int listener = ::socket(AF_INET, SOCK_STREAM, 0);
  if (listener < 0) return error = std::strerror(errno), -1;
  const int yes = 1;
  ::setsockopt(listener, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::bind(listener, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 || ::listen(listener, 1) != 0) {
    error = std::strerror(errno);
    ::close(listener);
    return -1;
  }
  const int client = ::accept(listener, nullptr, nullptr);
  if (client < 0) error = std::strerror(errno);
  ::close(listener);
  return client;
}

const char* KindName(v1::FaultInterval::Kind kind) {
  return v1::FaultInterval::Kind_Name(kind).c_str();
}

// What the operator reads: a line when the verdict changes, one per new
// fault interval, a progress line every `every_s` of the run, and the end.
class LivePrinter {
 public:
  LivePrinter(std::ostream& out, bool json) : out_(out), json_(json) {}

  void Print(const v1::LiveRun& live) {
    std::lock_guard lock(mutex_);
    if (json_) {
      auto text = api::ToJson(live);
      if (text.ok()) out_ << *text << "\n" << std::flush;
      return;
    }
    if (live.state() == v1::LiveRun::RECORDING && live.epoch_count() == 0) {
      out_ << live.name() << ": monitoring " << live.unit_serial() << " (planned "
           << absl::StrFormat("%.0f s", live.planned_duration_s()) << ")\n";
    }
    for (int i = 0; i < live.fault_intervals_size(); ++i) {
      const v1::FaultInterval& f = live.fault_intervals(i);
      const std::string key = absl::StrFormat("%s/%d/%.3f", f.channel(), static_cast<int>(f.kind()), f.start_s());
      if (!shown_.insert(key).second) continue;
      out_ << absl::StrFormat("t %8.1f s  %s on %s from %.1f s (statistic %.3g)\n", live.time_s(), KindName(f.kind()),
                              f.channel(), f.start_s(), f.peak_statistic());
    }
    const auto verdict = v1::AnalysisReport::Verdict_Name(live.verdict());
    const bool progress = live.time_s() >= next_progress_s_;
    if (live.epoch_count() > 0 && (verdict != verdict_ || progress)) {
      double worst = 0.0;
      std::string worst_channel = "-";
      for (const auto& c : live.channels()) {
        if (std::isfinite(c.window_ratio()) && c.window_ratio() > worst) worst = c.window_ratio(), worst_channel = c.name();
      }
      out_ << absl::StrFormat("t %8.1f s  epochs %d/%d  verdict %s  largest window F %.2f (%s; tolerance %.2f)\n",
                              live.time_s(), live.epoch_count(), live.planned_epoch_count(), verdict, worst,
                              worst_channel, live.eta2());
      verdict_ = verdict;
      while (next_progress_s_ <= live.time_s()) next_progress_s_ = live.time_s() + kProgressEveryS;
    }
    if (live.state() == v1::LiveRun::STORED) {
      out_ << "stored " << live.run() << "\n";
      if (!live.analysis().empty()) out_ << "analysis " << live.analysis() << "\n";
      if (live.has_error()) out_ << live.error().message() << "\n";
    }
    out_ << std::flush;
  }

 private:
  static constexpr double kProgressEveryS = 60.0;
  std::mutex mutex_;
  std::ostream& out_;
  bool json_;
  std::set<std::string> shown_;
  std::string verdict_;
  double next_progress_s_ = 0.0;
};

class StreamVerb final : public Verb {
 public:
  std::string Name() const override { return "stream"; }
  std::string Summary() const override {
    return "Monitor a test live as the bench records it, then store and analyse it";
  }

  void DeclareOptions(OptionSink& options) override {
    options.Positionals("SOURCE", &source_, "Bench-run CSV being written: a file, or - for stdin (the default)");
    options.Flag("--follow", &follow_, "Read on at the file's end until it has been idle for --idle-timeout");
    options.Option("--idle-timeout", &idle_timeout_s_, "Seconds without new lines that end a followed file (10)");
    options.Option("--listen", &listen_port_, "Read the lines from the first client of this TCP port on 127.0.0.1");
    options.Option("--planned-duration", &planned_duration_s_,
                   "The test's planned length in seconds; the family-wise thresholds count it (3600)");
    options.Flag("--stop-when-faulty", &stop_when_faulty_,
                 "End the test at the first FAULTY verdict; what was recorded is stored");
    options.Flag("--json", &json_, "Print each state as one JSON line (insdiag.v1.LiveRun)");
    options.Option("--request-id", &request_id_, "Idempotency key of the stored run (default: a new random key)");
    server_.Declare(options);
  }

  int Run(std::ostream& out, std::ostream& err) override {
    double planned_s = 3600.0, idle_s = 10.0;
    int port = 0;
    if (!planned_duration_s_.empty() && (!absl::SimpleAtod(planned_duration_s_, &planned_s) || !(planned_s > 0.0))) {
      return UsageError(err, Name(), "--planned-duration: expected a positive number of seconds");
    }
    if (!idle_timeout_s_.empty() && (!absl::SimpleAtod(idle_timeout_s_, &idle_s) || !(idle_s >= 0.0))) {
      return UsageError(err, Name(), "--idle-timeout: expected a number of seconds");
    }
    if (!listen_port_.empty() && (!absl::SimpleAtoi(listen_port_, &port) || port <= 0 || port > 65535)) {
      return UsageError(err, Name(), "--listen: expected a TCP port");
    }
    if (source_.size() > 1) return UsageError(err, Name(), "one SOURCE at most");
    const std::string path = source_.empty() ? "-" : source_.front();
    if (port > 0 && path != "-") return UsageError(err, Name(), "--listen reads from a socket, not from SOURCE");

    int fd = 0;
    std::string source_name = "stdin";
    if (port > 0) {
      std::string error;
      err << "insdiag stream: waiting for the bench on 127.0.0.1:" << port << "\n";
      fd = AcceptOneClient(port, error);
      if (fd < 0) return RequestFailed(err, Name(), "--listen", absl::UnavailableError(error));
      source_name = absl::StrFormat("127.0.0.1:%d", port);
    } else if (path != "-") {
      fd = ::open(path.c_str(), O_RDONLY);
      if (fd < 0) {
        err << path << ": cannot open: " << std::strerror(errno) << "\n";
        return kExitRefused;
      }
      source_name = path;
    }
    const int status = Stream(fd, source_name, planned_s, std::chrono::milliseconds(std::lround(idle_s * 1000.0)), out, err);
    if (fd > 0) ::close(fd);
    return status;
  }

 private:
  int Stream(int fd, const std::string& source_name, double planned_s, std::chrono::milliseconds idle_timeout,
             std::ostream& out, std::ostream& err) {
    LineSource lines(fd, follow_, idle_timeout);
    benchrun::BenchRunLineStream text(source_name);
    std::atomic<bool> stop{false};
    std::string line;
    // The metadata and header come before anything is sent.
    while (!text.started() && lines.Next(line, stop)) {
      if (auto status = text.AddLine(line); !status.ok()) {
        err << status.message() << "\n";
        return kExitRefused;
      }
    }
    if (!text.started()) {
      err << text.Finish().message() << "\n";
      return kExitRefused;
    }

    auto stub = v1::LiveRunService::NewStub(server_.Connect());
    grpc::ClientContext context;
    auto call = stub->MonitorRun(&context);
    v1::MonitorRunRequest request;
    request.set_planned_duration_s(planned_s);
    *request.mutable_upload()->mutable_metadata() = api::ToProto(text.run().metadata, text.run().has_temperature);
    request.mutable_upload()->mutable_metadata()->set_request_id(request_id_.empty() ? client::NewRequestId()
                                                                                      : request_id_);
    call->Write(request);
    request.clear_planned_duration_s();

    LivePrinter printer(out, json_);
    // The server answers every chunk; a few chunks in flight keep a source
    // read faster than real time (a file) from running ahead of the monitor,
    // so that --stop-when-faulty stops near the failure.
    std::mutex pace;
    std::condition_variable answered;
    long chunks_sent = 0, answers_read = -1;  // the first answer precedes any chunk
    std::thread answers([&] {
      v1::LiveRun live;
      while (call->Read(&live)) {
        printer.Print(live);
        if (stop_when_faulty_ && live.verdict() == v1::AnalysisReport::FAULTY) stop = true;
        std::lock_guard lock(pace);
        ++answers_read;
        answered.notify_all();
      }
      std::lock_guard lock(pace);
      answers_read = std::numeric_limits<long>::max();  // the call has ended
      answered.notify_all();
    });

    api::SampleDigest digest(text.run().has_temperature);
    v1::SampleChunk chunk;
    auto sent_at = Clock::now();
    bool writing = true;
    const auto flush = [&] {
      if (chunk.samples_size() == 0 || !writing) return;
      {
        std::unique_lock lock(pace);
        answered.wait(lock, [&] { return chunks_sent - answers_read < kChunksInFlight; });
      }
      *request.mutable_upload()->mutable_samples() = chunk;
      writing = call->Write(request);
      chunk.Clear();
      sent_at = Clock::now();
      std::lock_guard lock(pace);
      ++chunks_sent;
    };
    absl::Status refused;
    while (writing && !stop.load() && lines.Next(line, stop)) {
      if (refused = text.AddLine(line); !refused.ok()) break;
      for (const engine::ImuSample& sample : text.TakeSamples()) {
        digest.Add(sample);
        *chunk.add_samples() = api::ToProto(sample);
      }
      // Chunks of one update interval keep the monitor an epoch behind the
      // bench, however fast the source is read.
      const int n = chunk.samples_size();
      if (n > 0 && (chunk.samples(n - 1).t() - chunk.samples(0).t() >= kChunkRunTimeS || Clock::now() - sent_at > kChunkAge)) {
        flush();
      }
    }
    if (refused.ok() && !stop.load()) refused = text.Finish();
    if (!refused.ok()) {
      // Nothing half-done is stored: the stream is abandoned.
      context.TryCancel();
      answers.join();
      err << refused.message() << "\n";
      return kExitRefused;
    }
    flush();
    request.mutable_upload()->set_sha256(digest.HexDigest());
    if (writing) call->Write(request);
    call->WritesDone();
    answers.join();
    const grpc::Status finished = call->Finish();
    if (!finished.ok()) {
      return RequestFailed(err, Name(), server_.address,
                           absl::Status(static_cast<absl::StatusCode>(finished.error_code()), finished.error_message()));
    }
    if (stop.load()) err << "insdiag stream: stopped at the first FAULTY verdict; what was recorded is stored\n";
    return kExitOk;
  }

  static constexpr double kChunkRunTimeS = 1.0;  // the server monitor's update interval
  static constexpr long kChunksInFlight = 4;
  static constexpr std::chrono::milliseconds kChunkAge{200};

  std::vector<std::string> source_;
  bool follow_ = false;
  std::string idle_timeout_s_;
  std::string listen_port_;
  std::string planned_duration_s_;
  bool stop_when_faulty_ = false;
  bool json_ = false;
  std::string request_id_;
  ServerFlags server_;
};

}  // namespace

std::unique_ptr<Verb> MakeVerb_stream() { return std::make_unique<StreamVerb>(); }

}  // namespace insdiag::cli
