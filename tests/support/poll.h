// Waiting in tests by polling a condition, never by sleeping a fixed time and
// then counting: a test waits as long as the system takes, no longer, and
// fails with its own message when the condition never comes. Timeouts are
// generous bounds against a hang, not figures the test asserts.
#pragma once

#include <chrono>
#include <thread>

namespace insdiag::testing {

inline constexpr std::chrono::milliseconds kPollInterval{20};

// Checks `condition` until it holds (true) or `timeout` has passed (false).
template <typename Condition>
bool PollUntil(Condition&& condition, std::chrono::milliseconds timeout,
               std::chrono::milliseconds interval = kPollInterval) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    if (condition()) return true;
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(interval);
  }
}

// Checks that `condition` holds at every poll for `duration` (false at the
// first poll it does not): for what must not happen, e.g. a cancelled upload
// storing a run after all.
template <typename Condition>
bool HoldsThroughout(Condition&& condition, std::chrono::milliseconds duration,
                     std::chrono::milliseconds interval = kPollInterval) {
  const auto end = std::chrono::steady_clock::now() + duration;
  for (;;) {
    if (!condition()) return false;
    if (std::chrono::steady_clock::now() >= end) return true;
    std::this_thread::sleep_for(interval);
  }
}

}  // namespace insdiag::testing
