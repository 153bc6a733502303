#include "interrupt.hpp"

#include <csignal>

namespace dynamap {
namespace {
volatile std::sig_atomic_t g_interrupted = 0;
extern "C" void onSignal(int) { g_interrupted = 1; }
}  // namespace

void installInterruptHandler() {
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
}

bool interruptRequested() { return g_interrupted != 0; }

}  // namespace dynamap
