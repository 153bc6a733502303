// LoopClosureThread (core/src/tracking/loop_thread.cpp) as the realtime tracker drives it, on
// the loop room's drifting circle (tests/loop/loop_test_scene.hpp): the tracking thread adds
// keyframes and polls for corrections without waiting, a second thread (the BA's) sends pose
// updates of earlier keyframes meanwhile. The revisit's correction arrives, and a keyframe
// whose pose was updated is corrected from that pose. Under TSan this is the loop thread's
// race check (a whole tracker run with loop closure takes minutes there).
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "dynamap/core/tracking/loop_thread.hpp"
#include "loop_test_scene.hpp"

namespace dynamap {
namespace {

TEST(LoopClosureThread, KeyframesPoseUpdatesAndPollsFromTwoThreadsGiveTheRevisitsCorrection) {
  const TrackerConfig config;
  const PinholeCamera camera = cameraPreset("freiburg3");
  test::SyntheticScene scene(camera, 21);
  test::addLoopRoom(scene);
  const GridOrbExtractor orb(config);
  std::mt19937 rng(3);
  constexpr int kKeyframes = 60;  // 1.25 rounds
  std::vector<LoopKeyframeInput> keyframes;
  Eigen::Isometry3d estimate = test::circleKeyframePose(0);
  for (int k = 0; k < kKeyframes; ++k) {
    if (k > 0) {
      estimate = estimate * test::driftingStep(test::circleKeyframePose(k - 1),
                                               test::circleKeyframePose(k), rng);
    }
    const test::RenderedFrame f = scene.render(test::circleKeyframePose(k), 0.0);
    keyframes.push_back(test::makeLoopKeyframe(static_cast<std::uint64_t>(k), f, estimate, orb,
                                               config, true, rng));
  }

  LoopClosureThread loop(camera, config, LoopCloserConfig{}, nullptr);
  loop.start();
  std::atomic<int> added{0};
  std::atomic<bool> done{false};
  // The BA thread: re-sends the pose of a keyframe 3 behind the newest, unchanged.
  std::thread ba([&] {
    while (!done.load()) {
      const int k = added.load() - 3;
      if (k >= 0) {
        const auto& kf = keyframes[static_cast<std::size_t>(k)];
        loop.updatePose(kf.id, kf.T_W_C, 0);
      }
      std::this_thread::yield();
    }
  });
  std::vector<LoopCorrection> corrections;
  for (int k = 0; k < kKeyframes; ++k) {
    loop.addKeyframe(keyframes[static_cast<std::size_t>(k)]);
    added.store(k + 1);
    for (auto& c : loop.takeCorrections()) corrections.push_back(std::move(c));
  }
  for (auto& c : loop.waitIdle()) corrections.push_back(std::move(c));
  done.store(true);
  ba.join();
  loop.stop();

  const LoopThreadStats stats = loop.stats();
  EXPECT_EQ(stats.keyframes, static_cast<std::size_t>(kKeyframes));
  EXPECT_GE(stats.loops, 1u);
  ASSERT_EQ(corrections.size(), stats.closures);
  ASSERT_GE(corrections.size(), 1u) << "the revisit gave no correction";
  // Oldest first, each one's generation one more than the one before; the first one corrects
  // keyframe 0 from the pose it was added with.
  for (std::size_t i = 0; i < corrections.size(); ++i) {
    EXPECT_EQ(corrections[i].generation, static_cast<int>(i) + 1);
    ASSERT_FALSE(corrections[i].keyframes.empty());
  }
  const PoseCorrection& first = corrections.front().keyframes.front();
  EXPECT_EQ(first.id, 0u);
  EXPECT_TRUE(first.T_W_C_before.isApprox(keyframes[0].T_W_C, 1e-9));
  // The newest keyframe comes back nearer to the truth than its drifted estimate.
  const PoseCorrection& last = corrections.back().keyframes.back();
  const Eigen::Isometry3d truth = test::circleKeyframePose(static_cast<int>(last.id));
  EXPECT_LT((last.T_W_C_after.translation() - truth.translation()).norm(),
            (keyframes[last.id].T_W_C.translation() - truth.translation()).norm());
}

}  // namespace
}  // namespace dynamap
