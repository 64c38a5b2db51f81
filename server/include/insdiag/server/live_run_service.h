// insdiag.v1.LiveRunService, independent of transport (live.proto): a test
// monitored while the bench records it. Each MonitorRun stream feeds an
// upload (RunService::Upload, so the stored run is exactly an upload's) and a
// live monitor (engine/monitor/live_monitor.h) on the same samples, and
// publishes the monitor's state to the stream's client and to every watcher.
// When the stream completes, the run is stored and an analysis of it queued.
//
// Live state is kept in memory while the server runs: the tests being
// recorded and the most recent ended ones.
#pragma once

#include <absl/functional/function_ref.h>
#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "insdiag/kb/connection_pool.h"
#include "insdiag/server/kb_services.h"
#include "insdiag/server/run_service.h"
#include "insdiag/v1/live.pb.h"

namespace insdiag::server {

class LiveRunService {
 public:
  struct Options {
    std::size_t kept_ended = 20;  // ended tests still listed and watchable
    std::chrono::milliseconds watch_poll{250};  // how often a watcher checks that its client is there
  };

  LiveRunService(RunService& runs, AnalysisService& analyses, kb::ConnectionPool& pool, Options options)
      : runs_(runs), analyses_(analyses), pool_(pool), options_(options) {}

  // One MonitorRun stream: `next` reads the next request (false when the
  // client has finished or gone), `send` writes an answer (false when the
  // client has gone: the test is still recorded and stored), `cancelled`
  // tells a client that went away from one that finished. `last` receives
  // the final state (for the audit). Returns how the stream ends.
  absl::Status MonitorRun(absl::FunctionRef<bool(v1::MonitorRunRequest&)> next,
                          absl::FunctionRef<bool(const v1::LiveRun&)> send, absl::FunctionRef<bool()> cancelled,
                          v1::LiveRun& last);

  absl::StatusOr<v1::ListLiveRunsResponse> ListLiveRuns(const v1::ListLiveRunsRequest& request);
  // Calls `send` with the state now and on every change until the test
  // ends, `send` returns false or `stop()` is true.
  absl::Status WatchLiveRun(const v1::WatchLiveRunRequest& request, absl::FunctionRef<bool(const v1::LiveRun&)> send,
                            std::function<bool()> stop);

 private:
  struct Session {
    std::mutex mutex;
    std::condition_variable changed;
    v1::LiveRun state;
    std::uint64_t version = 0;
    bool ended = false;
  };

  std::shared_ptr<Session> Open(v1::LiveRun& state);
  void Publish(Session& session, const v1::LiveRun& state, bool ended);
  void Retire(const std::string& name);

  RunService& runs_;
  AnalysisService& analyses_;
  kb::ConnectionPool& pool_;
  Options options_;
  std::mutex mutex_;
  std::map<std::string, std::shared_ptr<Session>> sessions_;
  std::deque<std::string> ended_;  // oldest first
};

}  // namespace insdiag::server
