// Offline runs repeat exactly: the detector (dynamic.detector_lockstep) and bundle adjustment
// (tracking.ba_lockstep) hand their results to the tracker at points fixed by the frames, not by
// thread timing, so the same command gives the same trajectory, keyframes and masks.
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli_test_util.hpp"
#include "test_paths.hpp"

namespace dynamap {
namespace {

namespace fs = std::filesystem;

// The first 40 frames of teddy_dyn_dev (walkers in every frame), without its reference clouds:
// map metrics are not what this test is about, and they take most of a short run's time.
std::vector<std::string> dynDevArgs(const std::string& seq, const fs::path& out) {
  return {
      "run",          "--sequence", seq, "--out", out.string(), "--set", "mapping.backend=points",
      "--save-masks", "--quiet"};
}

TEST(Determinism, OfflineRunsWithDetectorAndBundleAdjustmentRepeatExactly) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  const std::string seq = test::makeTeddySubset("determinism_seq", 40, "dynamic/teddy_dyn_dev");
  std::vector<fs::path> outs;
  for (int i = 0; i < 2; ++i) {
    outs.push_back(test::freshTempDir("determinism_" + std::to_string(i)));
    const auto r = test::runDynamap(dynDevArgs(seq, outs.back()));
    ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  }
  for (const char* file : {"trajectory.txt", "keyframes.txt", "frames.txt"}) {
    const std::string a = test::readFile((outs[0] / file).string());
    EXPECT_FALSE(a.empty()) << file;
    EXPECT_EQ(a, test::readFile((outs[1] / file).string())) << file << " differs between runs";
  }
  std::size_t masks = 0;
  for (const auto& entry : fs::directory_iterator(outs[0] / "masks")) {
    ++masks;
    const fs::path other = outs[1] / "masks" / entry.path().filename();
    ASSERT_TRUE(fs::exists(other)) << other;
    EXPECT_EQ(test::readFile(entry.path().string()), test::readFile(other.string()))
        << entry.path().filename();
  }
  EXPECT_GE(masks, 5u);  // keyframes of 40 frames with walkers in every one
}

}  // namespace
}  // namespace dynamap
