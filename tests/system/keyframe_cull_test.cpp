// Keyframe culling (issue 47, point 2): a camera that walks the same path back and forth makes
// keyframes on its second pass (the first pass's keyframes are too recent for a revisit then);
// those that older keyframes already cover, and whose pose those keyframes' landmarks confirm,
// are culled at finish() (with tracking.kf_cull_online, once they leave the bundle-adjustment
// window): not listed, not saved, while every frame keeps its pose.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "dynamap/system.hpp"
#include "synthetic_scene.hpp"

namespace dynamap::keyframe_cull_test {
namespace {

constexpr int kFramesPerPass = 60;
constexpr double kPeriodS = 1.0 / 30.0;

/// Camera i of a walk to the right while turning (truth, scene frame).
Eigen::Isometry3d walkPose(int i) {
  const double s = static_cast<double>(i) / (kFramesPerPass - 1);
  return test::cameraPose({0.4 * s, 0.04 * std::sin(3.0 * s), 0.2 * s}, -12.0 + 24.0 * s, 3.0);
}

struct WalkRun {
  SystemCounts counts;
  std::size_t listed = 0;  ///< System::keyframes()
  double rms_m = 0.0;      ///< translation error against the truth, world = frame 0
};

/// The walk played forward then (`back`) backward, in one run; culled keyframes go when they
/// leave the window (`online`) or at finish().
WalkRun walkThereAndBack(bool cull, bool back = true, bool online = false) {
  AppConfig config;
  config.dynamic.mode = "off";
  config.tracking.kf_cull_redundant = cull;
  config.tracking.kf_cull_online = online;
  config.tracking.ba_window = 4;  // a short walk: keyframes leave the window soon
  test::SyntheticScene scene(config.resolvedCamera(), 21);
  scene.addDefaultRoom();
  System system(config);
  std::vector<int> order;
  for (int i = 0; i < kFramesPerPass; ++i) order.push_back(i);
  for (int i = kFramesPerPass - 1; back && i >= 0; --i) order.push_back(i);
  for (std::size_t j = 0; j < order.size(); ++j) {
    const auto r = scene.render(walkPose(order[j]), 0.0);
    RgbdFrame frame;
    frame.index = j;
    frame.timestamp_s = static_cast<double>(j) * kPeriodS;
    frame.bgr = r.bgr;
    frame.depth_m = r.depth_m;
    system.track(frame);
  }
  system.finish();
  WalkRun out;
  out.counts = system.counts();
  out.listed = system.keyframes().size();
  const auto trajectory = system.trajectory();
  double sum2 = 0.0;
  for (std::size_t j = 0; j < trajectory.size(); ++j) {
    const Eigen::Isometry3d truth = walkPose(0).inverse() * walkPose(order[j]);
    sum2 += (trajectory[j].T_W_C.translation() - truth.translation()).squaredNorm();
  }
  out.rms_m = std::sqrt(sum2 / static_cast<double>(trajectory.size()));
  return out;
}

TEST(KeyframeCulling, TheWayBackCullsItsRedundantKeyframesAndKeepsEveryPose) {
  const WalkRun culled = walkThereAndBack(true);
  const WalkRun kept = walkThereAndBack(false);
  std::printf("culling: %zu keyframes (%zu culled), RMS %.2f mm; without: %zu, RMS %.2f mm\n",
              culled.counts.keyframes, culled.counts.culled_keyframes, 1e3 * culled.rms_m,
              kept.counts.keyframes, 1e3 * kept.rms_m);
  EXPECT_EQ(kept.counts.culled_keyframes, 0u);
  EXPECT_GT(culled.counts.culled_keyframes, 0u);
  EXPECT_LT(culled.counts.keyframes, kept.counts.keyframes);
  EXPECT_EQ(culled.listed, culled.counts.keyframes);  // culled ones are not listed
  // Every frame keeps a pose, as good as without culling (this walk: ~1-2 mm RMS).
  EXPECT_EQ(culled.counts.lost, 0u);
  EXPECT_LT(culled.rms_m, 0.01);
  EXPECT_LT(culled.rms_m, kept.rms_m + 0.002);
}

// Culled during the run, the way back's last keyframes never leave the window (no newer keyframe
// comes): finish() culls them too. Either way there and back keep at most 1.3 x the keyframes of
// the way there, issue 47's bound for revisits (measured: 8 there, 10 there and back both ways;
// before finish() culled, 14).
TEST(KeyframeCulling, FinishCullsTheRedundantKeyframesStillInTheWindow) {
  const WalkRun there = walkThereAndBack(true, false);
  for (const bool online : {false, true}) {
    const WalkRun there_and_back = walkThereAndBack(true, true, online);
    std::printf("online %d: keyframes there %zu, there and back %zu (%zu culled), RMS %.2f mm\n",
                online, there.counts.keyframes, there_and_back.counts.keyframes,
                there_and_back.counts.culled_keyframes, 1e3 * there_and_back.rms_m);
    EXPECT_LE(static_cast<double>(there_and_back.counts.keyframes),
              1.3 * static_cast<double>(there.counts.keyframes))
        << online;
    EXPECT_LT(there_and_back.rms_m, 0.01) << online;
  }
}

}  // namespace
}  // namespace dynamap::keyframe_cull_test
