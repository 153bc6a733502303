// blendReferenceSwitches() (core/include/dynamap/core/tracking/reference_blend.hpp): where the
// reference keyframe changes, the jump between the two keyframes' corrections is spread over the
// frames since the previous change, so the trajectory has no step there.
#include <gtest/gtest.h>

#include <cmath>

#include "dynamap/core/tracking/reference_blend.hpp"

namespace dynamap {
namespace {

Eigen::Isometry3d shift(double x, double y, double z) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

/// 10 frames at 30 Hz, 1 cm apart along x; frames 0-4 reference keyframe 0 (not moved by bundle
/// adjustment), frames 5-9 keyframe 1, which bundle adjustment moved `moved` after they were
/// tracked.
std::vector<ReferencedFrame> twoKeyframes(const Eigen::Isometry3d& moved) {
  std::vector<ReferencedFrame> frames(10);
  for (int i = 0; i < 10; ++i) {
    ReferencedFrame& f = frames[static_cast<std::size_t>(i)];
    f.timestamp_s = i / 30.0;
    f.has_ref = true;
    f.ref_kf = i < 5 ? 0 : 1;
    f.T_W_C_tracked = shift(0.01 * i, 0.0, 0.0);
    f.correction = i < 5 ? Eigen::Isometry3d::Identity() : moved;
  }
  return frames;
}

TEST(ReferenceBlend, SpreadsTheJumpAtASwitchOverTheFramesBeforeIt) {
  const auto frames = twoKeyframes(shift(0.0, 0.02, 0.0));  // keyframe 1 moved 2 cm along y
  const auto poses = blendReferenceSwitches(frames);
  ASSERT_EQ(poses.size(), frames.size());
  // Frame 0 and the frames of keyframe 1 keep their own corrections (to 1e-12 m).
  EXPECT_NEAR(poses[0].translation().y(), 0.0, 1e-12);
  for (std::size_t i = 5; i < 10; ++i) EXPECT_NEAR(poses[i].translation().y(), 0.02, 1e-12);
  // Frames 1-4 take 1/5 ... 4/5 of the jump: y rises by 4 mm a frame, no 2 cm step at frame 5.
  for (std::size_t i = 1; i < 5; ++i) {
    EXPECT_NEAR(poses[i].translation().y(), 0.004 * static_cast<double>(i), 1e-9) << i;
  }
  for (std::size_t i = 1; i < 10; ++i) {
    const double step = (poses[i].translation() - poses[i - 1].translation()).norm();
    EXPECT_LT(step, 0.0111) << "frame " << i;  // the 1 cm of motion and at most 4 mm across
  }
  // x, the tracked motion, is untouched by a correction along y.
  for (std::size_t i = 0; i < 10; ++i) {
    EXPECT_NEAR(poses[i].translation().x(), 0.01 * static_cast<double>(i), 1e-12);
  }
}

TEST(ReferenceBlend, SpreadsARotationBySlerp) {
  Eigen::Isometry3d turned = Eigen::Isometry3d::Identity();
  turned.linear() = Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const auto poses = blendReferenceSwitches(twoKeyframes(turned));
  for (std::size_t i = 0; i < 5; ++i) {
    const double angle = Eigen::AngleAxisd(poses[i].linear()).angle();
    EXPECT_NEAR(angle, 0.05 * static_cast<double>(i) / 5.0, 1e-9) << i;
  }
  EXPECT_NEAR(Eigen::AngleAxisd(poses[5].linear()).angle(), 0.05, 1e-12);
}

TEST(ReferenceBlend, AFrameWithoutReferenceKeepsItsPoseAndEndsTheSpan) {
  auto frames = twoKeyframes(shift(0.0, 0.02, 0.0));
  frames[3].has_ref = false;  // lost: its tracked pose, and frame 4 alone before the switch
  frames[3].correction = shift(0.0, 0.5, 0.0);  // ignored without a reference
  const auto poses = blendReferenceSwitches(frames);
  EXPECT_NEAR(poses[3].translation().y(), 0.0, 1e-12);
  EXPECT_NEAR(poses[2].translation().y(), 0.0, 1e-12);  // span 0-2 ended by the lost frame
  EXPECT_NEAR(poses[4].translation().y(), 0.0, 1e-12);  // span 4-4: the switch's first share
  EXPECT_NEAR(poses[5].translation().y(), 0.02, 1e-12);
}

TEST(ReferenceBlend, WithoutSwitchesEachFrameFollowsItsReference) {
  auto frames = twoKeyframes(shift(0.0, 0.0, 0.0));
  for (auto& f : frames) {
    f.ref_kf = 7;
    f.correction = shift(0.1, 0.2, 0.3);
  }
  const auto poses = blendReferenceSwitches(frames);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_TRUE(poses[i].isApprox(frames[i].correction * frames[i].T_W_C_tracked, 1e-12)) << i;
  }
}

}  // namespace
}  // namespace dynamap
