// The fleet statistics' materialised views (kb/fleet_store.h) refreshed on a
// schedule inside insdiagd: one thread, one refresh every period, a failure
// logged and tried again at the next. Any number of insdiagd processes may
// share one database: RefreshViews' advisory lock lets one refresh at a time.
#pragma once

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "insdiag/kb/connection_pool.h"

namespace insdiag::server {

class FleetViewRefresher {
 public:
  // `period` 0: never refresh. `pool` must outlive the refresher.
  FleetViewRefresher(kb::ConnectionPool& pool, std::chrono::milliseconds period);
  ~FleetViewRefresher();  // Stop()
  void Start();
  // Stops scheduling; waits for a refresh under way to finish.
  void Stop();

 private:
  void Run();

  kb::ConnectionPool& pool_;
  const std::chrono::milliseconds period_;
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
};

}  // namespace insdiag::server
