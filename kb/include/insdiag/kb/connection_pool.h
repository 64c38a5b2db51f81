// A small pool of PostgreSQL connections shared by request handlers.
//
// Acquire() hands out a lease that returns its connection on destruction;
// broken connections are dropped and replaced by new ones on demand. At most
// `max_connections` exist at once; further Acquire() calls wait.
#pragma once

#include <absl/status/statusor.h>

#include <condition_variable>
#include <cstddef>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "insdiag/kb/pg.h"

namespace insdiag::kb {

class ConnectionPool {
 public:
  struct Options {
    std::string database_url;
    std::size_t max_connections = 8;
  };

  // Connects once to check the URL; UNAVAILABLE when the server is unreachable.
  static absl::StatusOr<std::unique_ptr<ConnectionPool>> Create(Options options);

  class Lease {
   public:
    Lease(Lease&& other) noexcept;
    Lease& operator=(Lease&&) = delete;
    Lease(const Lease&) = delete;
    ~Lease();
    Connection& operator*() { return *connection_; }
    Connection* operator->() { return connection_.get(); }

   private:
    friend class ConnectionPool;
    Lease(ConnectionPool* pool, std::unique_ptr<Connection> connection)
        : pool_(pool), connection_(std::move(connection)) {}
    ConnectionPool* pool_;
    std::unique_ptr<Connection> connection_;
  };

  absl::StatusOr<Lease> Acquire();

  const std::string& database_url() const { return options_.database_url; }

  // Connections open (idle and leased), idle, and the most the pool opens.
  struct Usage {
    std::size_t open = 0, idle = 0, max = 0;
  };
  Usage usage();

 private:
  explicit ConnectionPool(Options options) : options_(std::move(options)) {}
  void Release(std::unique_ptr<Connection> connection);

  Options options_;
  std::mutex mutex_;
  std::condition_variable available_;
  std::vector<std::unique_ptr<Connection>> idle_;
  std::size_t open_ = 0;  // idle + leased
};

}  // namespace insdiag::kb
