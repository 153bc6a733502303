#pragma once

namespace dynamap {

/// Installs a SIGINT/SIGTERM handler that only sets a flag; the run loop polls it and stops
/// cleanly, writing everything computed so far.
void installInterruptHandler();
bool interruptRequested();

}  // namespace dynamap
