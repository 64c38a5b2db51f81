#include "insdiag/server/fleet_view_refresher.h"

#include <absl/strings/str_cat.h>

#include "insdiag/kb/fleet_store.h"
#include "insdiag/server/server_log.h"

namespace insdiag::server {

FleetViewRefresher::FleetViewRefresher(kb::ConnectionPool& pool, std::chrono::milliseconds period)
    : pool_(pool), period_(period) {}

FleetViewRefresher::~FleetViewRefresher() { Stop(); }

void FleetViewRefresher::Start() {
  std::lock_guard lock(mutex_);
  if (period_.count() <= 0 || thread_.joinable() || stopping_) return;
  thread_ = std::thread([this] { Run(); });
}

void FleetViewRefresher::Stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void FleetViewRefresher::Run() {
  kb::FleetStore fleet(pool_);
  for (;;) {
    {
      std::unique_lock lock(mutex_);
      if (wake_.wait_for(lock, period_, [this] { return stopping_; })) return;
    }
    if (auto refreshed = fleet.RefreshViews(); !refreshed.ok()) {
      Log(LogLevel::kError, absl::StrCat("fleet views not refreshed: ", refreshed.status().message()));
    }
  }
}

}  // namespace insdiag::server
