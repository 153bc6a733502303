#pragma once

#include <string>
#include <vector>

namespace dynamap::test {

struct CommandResult {
  int exit_code = -1;
  std::string out;  ///< stdout
  std::string err;  ///< stderr
};

/// Runs build/bin/dynamap with `args` (no shell), waits, and captures its output.
/// With interrupt_after_s > 0, sends SIGINT after that many seconds.
CommandResult runDynamap(const std::vector<std::string>& args, double interrupt_after_s = 0.0);

std::string readFile(const std::string& path);
std::size_t countDataLines(const std::string& path);  ///< non-empty lines not starting with '#'

/// A TUM sequence folder with the first `frames` frames of the real teddy sequence (images are
/// symlinks) and its ground truth.
std::string makeTeddySubset(const std::string& name, std::size_t frames,
                            const std::string& source = "tum/rgbd_dataset_freiburg3_teddy");

}  // namespace dynamap::test
