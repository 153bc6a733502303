#pragma once

#include <exception>
#include <thread>

namespace dynamap {

/// Runs job(0) on another thread and job(1) on this one (the machine's 2 cores), then joins.
/// An exception from either job is rethrown here once both have ended (the first one's, if both
/// threw). The jobs must touch disjoint data.
template <typename Job>
void inTwo(const Job& job) {
  std::exception_ptr other_failed;
  std::thread other([&] {
    try {
      job(0);
    } catch (...) {
      other_failed = std::current_exception();
    }
  });
  try {
    job(1);
  } catch (...) {
    other.join();
    throw;
  }
  other.join();
  if (other_failed) std::rethrow_exception(other_failed);
}

}  // namespace dynamap
