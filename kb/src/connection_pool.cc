#include "insdiag/kb/connection_pool.h"

#include "insdiag/engine/status_macros.h"

namespace insdiag::kb {

absl::StatusOr<std::unique_ptr<ConnectionPool>> ConnectionPool::Create(Options options) {
  if (options.max_connections == 0) options.max_connections = 1;
  std::unique_ptr<ConnectionPool> pool(new ConnectionPool(std::move(options)));
  INSDIAG_ASSIGN_OR_RETURN(auto first, Connection::Open(pool->options_.database_url));
  pool->idle_.push_back(std::make_unique<Connection>(std::move(first)));
  pool->open_ = 1;
  return pool;
}

absl::StatusOr<ConnectionPool::Lease> ConnectionPool::Acquire() {
  std::unique_lock lock(mutex_);
  available_.wait(lock, [&] { return !idle_.empty() || open_ < options_.max_connections; });
  if (!idle_.empty()) {
    auto connection = std::move(idle_.back());
    idle_.pop_back();
    return Lease(this, std::move(connection));
  }
  ++open_;
  lock.unlock();
  // Connect outside the lock: it takes a round trip or more.
  auto connection = Connection::Open(options_.database_url);
  if (!connection.ok()) {
    lock.lock();
    --open_;
    available_.notify_one();
    return connection.status();
  }
  return Lease(this, std::make_unique<Connection>(std::move(*connection)));
}

void ConnectionPool::Release(std::unique_ptr<Connection> connection) {
  std::lock_guard lock(mutex_);
  if (connection->healthy()) {
    idle_.push_back(std::move(connection));
  } else {
    --open_;
  }
  available_.notify_one();
}

ConnectionPool::Lease::Lease(Lease&& other) noexcept
    : pool_(other.pool_), connection_(std::move(other.connection_)) {}

ConnectionPool::Lease::~Lease() {
  if (connection_) pool_->Release(std::move(connection_));
}

ConnectionPool::Usage ConnectionPool::usage() {
  std::lock_guard lock(mutex_);
  return Usage{open_, idle_.size(), options_.max_connections};
}

}  // namespace insdiag::kb
