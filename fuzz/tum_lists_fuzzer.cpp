// libFuzzer target: TUM list files. Mode byte, then rgb.txt "\n====\n" depth.txt.
// Even modes: TumSequence::open (list parsing + timestamp association). Odd modes: the same
// text as a trajectory file (readTrajectory, then write + read back). Only DatasetError may
// come out of the readers.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_util.hpp"
#include "trajectory_io.hpp"
#include "tum_dataset.hpp"

namespace {

using dynamap::fuzz::fail;

void openSequence(std::uint8_t mode, const std::vector<std::string>& parts) {
  const std::string dir = dynamap::fuzz::scratchDir();
  dynamap::fuzz::writeScratch("rgb.txt", parts[0]);
  dynamap::fuzz::writeScratch("depth.txt", parts.size() > 1 ? parts[1] : std::string());
  dynamap::DatasetOptions options;
  options.max_time_diff_s = 0.005 * ((mode >> 1) & 7);  // 0 .. 0.035
  options.keep_unassociated_rgb = (mode & 16) != 0;
  options.max_frames = (mode & 32) ? 3 : 0;
  try {
    const dynamap::TumSequence seq = dynamap::TumSequence::open(dir, options);
    const auto& entries = seq.entries();
    for (std::size_t i = 1; i < entries.size(); ++i) {
      if (!(entries[i - 1].rgb_timestamp_s < entries[i].rgb_timestamp_s)) {
        fail("entries not sorted by colour timestamp");
      }
    }
    for (const auto& e : entries) {
      if (!e.depth_path.empty() &&
          !(std::abs(e.rgb_timestamp_s - e.depth_timestamp_s) < options.max_time_diff_s)) {
        fail("associated pair outside the time window");
      }
    }
    if (options.max_frames > 0 && entries.size() > 3) fail("max_frames ignored");
  } catch (const dynamap::DatasetError&) {
  }
}

void readTrajectoryFile(const std::vector<std::string>& parts) {
  const std::string path = dynamap::fuzz::writeScratch("trajectory.txt", parts[0]);
  std::vector<dynamap::TimedPose> poses;
  try {
    poses = dynamap::readTrajectory(path);
  } catch (const dynamap::DatasetError&) {
    return;
  }
  for (std::size_t i = 1; i < poses.size(); ++i) {
    if (!(poses[i - 1].timestamp_s < poses[i].timestamp_s)) fail("trajectory not sorted");
  }
  for (const auto& p : poses) {
    if (!p.T_W_C.matrix().allFinite()) fail("non-finite pose read");
    (void)dynamap::formatTumPose(p);
  }
  // Written trajectories must read back (6-decimal timestamps may merge close stamps).
  const std::string out = dynamap::fuzz::scratchDir() + "/written.txt";
  dynamap::writeTrajectory(out, poses);
  try {
    const auto again = dynamap::readTrajectory(out);
    if (again.size() > poses.size()) fail("trajectory grew on write + read");
  } catch (const dynamap::DatasetError& e) {
    fail(std::string("written trajectory does not read back: ") + e.what());
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::uint8_t mode = data[0];
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  const auto parts = dynamap::fuzz::splitParts(text, dynamap::fuzz::kSeparator, 2);
  if (mode & 1) {
    readTrajectoryFile(parts);
  } else {
    openSequence(mode, parts);
  }
  return 0;
}
