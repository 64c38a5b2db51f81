#include "insdiag/server/live_run_service.h"

#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>
#include <google/protobuf/util/time_util.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "insdiag/api/report_codec.h"
#include "insdiag/engine/analysis.h"
#include "insdiag/engine/monitor/live_monitor.h"
#include "insdiag/engine/status_macros.h"
#include "insdiag/server/unit_type_models.h"

namespace insdiag::server {
namespace {

using google::protobuf::util::TimeUtil;

constexpr char kLiveRunPrefix[] = "liveRuns/";

// A random (version 4) UUID.
std::string NewUuid() {
  static thread_local std::mt19937_64 rng{std::random_device{}()};
  const std::uint64_t high = (rng() & 0xffffffffffff0fffULL) | 0x0000000000004000ULL;
  const std::uint64_t low = (rng() & 0x3fffffffffffffffULL) | 0x8000000000000000ULL;
  return absl::StrFormat("%08x-%04x-%04x-%04x-%012x", high >> 32, (high >> 16) & 0xffff, high & 0xffff, low >> 48,
                         low & 0xffffffffffffULL);
}

void Fill(const engine::LiveStatus& status, v1::LiveRun& out) {
  out.set_sample_count(status.samples);
  out.set_epoch_count(status.epochs);
  out.set_planned_epoch_count(status.planned_epochs);
  out.set_time_s(status.time_s);
  out.clear_channels();
  for (int c = 0; c < engine::kChannelCount; ++c) {
    v1::LiveChannel* channel = out.add_channels();
    channel->set_name(std::string(engine::kChannelNames[static_cast<size_t>(c)]));
    channel->set_beta2(status.beta2[static_cast<size_t>(c)]);
    channel->set_window_ratio(status.window_ratio[static_cast<size_t>(c)]);
  }
  out.clear_fault_intervals();
  for (const engine::FaultInterval& f : status.faults) *out.add_fault_intervals() = api::ToProto(f);
  out.set_verdict(api::ToProto(status.verdict));
  out.set_nis_mean(status.nis_mean);
  out.set_nis_band_low(status.nis_band_low);
  out.set_nis_band_high(status.nis_band_high);
  out.set_gamma2(status.gamma2);
  out.set_eta2(status.eta2);
  out.set_outlier_threshold(status.outlier_threshold);
  out.set_gradual_threshold(status.gradual_threshold);
  *out.mutable_update_time() = TimeUtil::GetCurrentTime();
}

}  // namespace

std::shared_ptr<LiveRunService::Session> LiveRunService::Open(v1::LiveRun& state) {
  auto session = std::make_shared<Session>();
  state.set_name(absl::StrCat(kLiveRunPrefix, NewUuid()));
  state.set_state(v1::LiveRun::RECORDING);
  *state.mutable_start_time() = TimeUtil::GetCurrentTime();
  *state.mutable_update_time() = TimeUtil::GetCurrentTime();
  session->state = state;
  std::lock_guard lock(mutex_);
  sessions_[state.name()] = session;
  return session;
}

void LiveRunService::Publish(Session& session, const v1::LiveRun& state, bool ended) {
  {
    std::lock_guard lock(session.mutex);
    session.state = state;
    ++session.version;
    session.ended = ended;
  }
  session.changed.notify_all();
  if (ended) Retire(state.name());
}

void LiveRunService::Retire(const std::string& name) {
  std::lock_guard lock(mutex_);
  ended_.push_back(name);
  while (ended_.size() > options_.kept_ended) {
    sessions_.erase(ended_.front());
    ended_.pop_front();
  }
}

absl::Status LiveRunService::MonitorRun(absl::FunctionRef<bool(v1::MonitorRunRequest&)> next,
                                        absl::FunctionRef<bool(const v1::LiveRun&)> send,
                                        absl::FunctionRef<bool()> cancelled, v1::LiveRun& last) {
  v1::MonitorRunRequest request;
  if (!next(request)) return absl::InvalidArgumentError("the stream ended before its metadata");
  if (!request.upload().has_metadata()) {
    return absl::InvalidArgumentError("metadata must be the first message of a monitored run");
  }
  const double planned_duration_s = request.planned_duration_s();
  if (!(std::isfinite(planned_duration_s) && planned_duration_s > 0.0)) {
    return absl::InvalidArgumentError(
        "planned_duration_s: the test's planned length in seconds must be given with the metadata, and positive");
  }
  RunService::Upload upload = runs_.StartUpload();
  INSDIAG_RETURN_IF_ERROR(upload.Accept(request.upload()));
  const engine::BenchRun& run = upload.received();
  INSDIAG_ASSIGN_OR_RETURN(auto nominal, NominalModelOfUnitType(pool_, run.metadata.unit_type));
  auto model = engine::APrioriModel(run, nominal, engine::AnalysisOptions{}.reference);
  if (!model.ok()) {
    return absl::FailedPreconditionError(
        absl::StrCat("live monitoring needs the unit's a-priori model (a datasheet in the metadata or a unit type "
                     "the knowledge base knows); an upload of the run is analysed without one: ",
                     model.status().message()));
  }
  engine::LiveMonitorOptions options;
  options.planned_duration_s = planned_duration_s;
  INSDIAG_ASSIGN_OR_RETURN(auto monitor, engine::LiveMonitor::Create(run, *model, options));
  engine::LiveMonitor& live = *monitor;

  v1::LiveRun state;
  state.set_unit_serial(run.metadata.unit_serial);
  state.set_planned_duration_s(planned_duration_s);
  const std::shared_ptr<Session> session = Open(state);
  bool client_listens = send(state);

  absl::Status status;
  while (status.ok() && next(request)) {
    status = upload.Accept(request.upload());
    if (!status.ok() || !request.upload().has_samples()) continue;
    auto epochs = live.Advance();
    if (!epochs.ok()) {
      status = epochs.status();
      continue;
    }
    if (*epochs > 0) {
      Fill(live.Status(), state);
      Publish(*session, state, false);
    } else {
      state.set_sample_count(run.samples.size());
    }
    // Every chunk is answered: the client paces itself by the answers.
    if (client_listens) client_listens = send(state);
  }
  // Read() also ends when the client cancels or the connection drops: such
  // a test is not finished and stores nothing.
  if (status.ok() && cancelled()) status = absl::CancelledError("the test was cancelled; nothing was stored");
  if (status.ok() && live.Finish().ok()) Fill(live.Status(), state);
  absl::StatusOr<v1::Run> stored = status.ok() ? upload.Finish() : absl::StatusOr<v1::Run>(status);
  if (stored.ok()) {
    state.set_state(v1::LiveRun::STORED);
    state.set_run(stored->name());
    v1::CreateAnalysisRequest analyse;
    analyse.mutable_analysis()->set_run(stored->name());
    auto analysis = analyses_.CreateAnalysis(analyse);
    if (analysis.ok()) {
      state.set_analysis(analysis->name());
    } else {
      state.mutable_error()->set_code(static_cast<int>(analysis.status().code()));
      state.mutable_error()->set_message(
          absl::StrCat("stored, but its analysis was not queued: ", analysis.status().message()));
    }
  } else {
    state.set_state(v1::LiveRun::FAILED);
    state.mutable_error()->set_code(static_cast<int>(stored.status().code()));
    state.mutable_error()->set_message(std::string(stored.status().message()));
  }
  *state.mutable_update_time() = TimeUtil::GetCurrentTime();
  Publish(*session, state, true);
  if (client_listens) send(state);
  last = state;
  return stored.status();
}

absl::StatusOr<v1::ListLiveRunsResponse> LiveRunService::ListLiveRuns(const v1::ListLiveRunsRequest& /*request*/) {
  std::vector<std::shared_ptr<Session>> sessions;
  {
    std::lock_guard lock(mutex_);
    for (const auto& [name, session] : sessions_) sessions.push_back(session);
  }
  v1::ListLiveRunsResponse response;
  for (const auto& session : sessions) {
    std::lock_guard lock(session->mutex);
    *response.add_live_runs() = session->state;
  }
  auto* runs = response.mutable_live_runs();
  std::sort(runs->begin(), runs->end(),
            [](const v1::LiveRun& a, const v1::LiveRun& b) { return b.start_time() < a.start_time(); });
  return response;
}

absl::Status LiveRunService::WatchLiveRun(const v1::WatchLiveRunRequest& request,
                                          absl::FunctionRef<bool(const v1::LiveRun&)> send,
                                          std::function<bool()> stop) {
  if (!request.name().starts_with(kLiveRunPrefix) || request.name().size() == sizeof kLiveRunPrefix - 1) {
    return absl::InvalidArgumentError(absl::StrCat("name: '", request.name(), "' is not a live run (liveRuns/{id})"));
  }
  std::shared_ptr<Session> session;
  {
    std::lock_guard lock(mutex_);
    const auto found = sessions_.find(request.name());
    if (found == sessions_.end()) {
      return absl::NotFoundError(absl::StrCat(request.name(), " is not being recorded and did not end recently"));
    }
    session = found->second;
  }
  std::uint64_t sent_version = 0;
  bool first = true;
  while (true) {
    v1::LiveRun state;
    bool ended = false;
    {
      std::unique_lock lock(session->mutex);
      session->changed.wait_for(lock, options_.watch_poll,
                                [&] { return first || session->version != sent_version; });
      if (!first && session->version == sent_version) {
        lock.unlock();
        if (stop()) return absl::OkStatus();
        continue;
      }
      state = session->state;
      sent_version = session->version;
      ended = session->ended;
    }
    first = false;
    if (!send(state) || ended || stop()) return absl::OkStatus();
  }
}

}  // namespace insdiag::server
