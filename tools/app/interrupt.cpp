#include "interrupt.hpp"

#include <atomic>
#include <csignal>

namespace dynamap {
namespace {
// The handler may run on any thread of the process (the frame reader's, a worker's), not only
// on the one that polls: a lock-free atomic, not a volatile sig_atomic_t, makes the flag safe
// across threads and is async-signal-safe.
std::atomic<bool> g_interrupted{false};
static_assert(std::atomic<bool>::is_always_lock_free);
extern "C" void onSignal(int) { g_interrupted.store(true, std::memory_order_relaxed); }
}  // namespace

void installInterruptHandler() {
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
}

bool interruptRequested() { return g_interrupted.load(std::memory_order_relaxed); }

}  // namespace dynamap
