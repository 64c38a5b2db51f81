// Independent filter passes on every core: ParallelMap(n, f) returns
// {f(0), …, f(n − 1)} in index order, whatever the schedule, so a result
// reduced from it in index order is the single-threaded one.
//
// The thread count comes from the machine (std::thread::hardware_concurrency),
// or from the environment's INSDIAG_THREADS (1: single-threaded). A map
// inside another map runs serially on its caller's thread: the outer one
// already holds the cores.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

namespace insdiag::engine::numerics {

// The threads a map may use: INSDIAG_THREADS when set to a positive integer,
// else the machine's hardware threads (at least one).
int WorkerThreads();

namespace detail {
// Whether the calling thread is one of a map's workers.
bool& InsideParallelMap();
}  // namespace detail

template <typename Fn>
auto ParallelMap(std::size_t n, const Fn& fn) -> std::vector<decltype(fn(std::size_t{}))> {
  using Result = decltype(fn(std::size_t{}));
  std::vector<Result> out(n);
  const std::size_t threads = std::min(n, static_cast<std::size_t>(WorkerThreads()));
  if (threads <= 1 || detail::InsideParallelMap()) {
    for (std::size_t i = 0; i < n; ++i) out[i] = fn(i);
    return out;
  }
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    detail::InsideParallelMap() = true;
    for (std::size_t i = next.fetch_add(1); i < n; i = next.fetch_add(1)) out[i] = fn(i);
    detail::InsideParallelMap() = false;
  };
  std::vector<std::jthread> pool;
  pool.reserve(threads - 1);
  for (std::size_t t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (std::jthread& t : pool) t.join();  // every worker done before `out` is returned
  return out;
}

// Runs `side` on a worker while the caller runs `main`; both are done on
// return. With one thread, or inside a map, `side` then `main` on the caller's.
template <typename Main, typename Side>
void InParallel(const Main& main, const Side& side) {
  if (WorkerThreads() <= 1 || detail::InsideParallelMap()) {
    side();
    main();
    return;
  }
  std::jthread worker([&] {
    detail::InsideParallelMap() = true;
    side();
  });
  // Both tasks hold a core: a map inside either runs serially.
  detail::InsideParallelMap() = true;
  main();
  detail::InsideParallelMap() = false;
}

// Runs `side` on a thread of its own while the caller runs `main`; both are
// done on return. Unlike InParallel, a map inside either still spreads over
// every core: for two tasks that are each mostly one chain of passes, one
// after the other, with a few independent passes between (the cores are
// oversubscribed while both map). With one thread, or inside a map, `side`
// then `main` on the caller's.
template <typename Main, typename Side>
void AlongsideEachOther(const Main& main, const Side& side) {
  if (WorkerThreads() <= 1 || detail::InsideParallelMap()) {
    side();
    main();
    return;
  }
  std::jthread worker([&] { side(); });
  main();
}

}  // namespace insdiag::engine::numerics
