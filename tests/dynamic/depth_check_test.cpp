// The dense geometric check (depth_check.hpp) on synthetic scenes with known geometry: a still
// room seen from two poses, and a textured box pushed across the floor that no detector knows.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "dynamap/core/dynamic/depth_check.hpp"
#include "synthetic_scene.hpp"

namespace dynamap {
namespace {

constexpr double kFramePeriodS = 1.0 / 30.0;

cv::Matx44d toMatx(const Eigen::Isometry3d& T) {
  cv::Matx44d m;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m(r, c) = T.matrix()(r, c);
  return m;
}

/// A hand-held camera drifting sideways and turning a little (about 2 cm and 0.4 deg a frame).
Eigen::Isometry3d cameraAt(int frame) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.02 * frame, -0.005 * frame, 0.01 * frame);
  T.linear() = Eigen::AngleAxisd(0.007 * frame, Eigen::Vector3d::UnitY()).toRotationMatrix();
  return T;
}

cv::Vec4d intrinsics(const PinholeCamera& c) { return {c.fx, c.fy, c.cx, c.cy}; }

DepthView viewOf(const test::RenderedFrame& f, const Eigen::Isometry3d& T_W_C, long frame) {
  DepthView v = DepthHistory::halfView(f.depth_m, frame);
  v.T_W_C = toMatx(T_W_C);
  return v;
}

struct PushedBox {
  PinholeCamera camera = cameraPreset("freiburg3");
  test::SyntheticScene scene{camera, 21};
  PushedBox() {
    scene.addDefaultRoom();
    // 60 cm box on the floor (y = 1.3 is the floor, y down), pushed at 0.6 m/s along x.
    scene.addMovingBox({0.0, 1.0, 3.0}, {0.3, 0.3, 0.3}, {0.6, 0.0, 0.0});
  }
  test::RenderedFrame at(int frame) const {
    return scene.render(cameraAt(frame), frame * kFramePeriodS);
  }
};

TEST(DepthCheck, SensorNoiseGrowsWithTheSquareOfDepth) {
  EXPECT_NEAR(depthNoiseM(0.4), 0.0012, 1e-9);
  EXPECT_NEAR(depthNoiseM(3.4), 0.0012 + 0.0019 * 9.0, 1e-9);
}

TEST(DepthCheck, WindowInteriorDepthRejectsPointsWhoseWindowTakesInAnOccludingEdge) {
  // A person 2 m away, a crate 1 m away covering x >= 320, a hole at (100, 100).
  cv::Mat depth(480, 640, CV_32F, cv::Scalar(2.f));
  depth(cv::Rect(320, 0, 320, 480)).setTo(1.f);
  depth.at<float>(100, 100) = 0.f;
  EXPECT_FLOAT_EQ(windowInteriorDepth(depth, 200, 240, 8, 0.1f), 2.f);
  // 6 px from the crate: interiorDepth() (4 px) takes it, an 8 px window does not.
  EXPECT_FLOAT_EQ(interiorDepth(depth, 314, 240), 2.f);
  EXPECT_FLOAT_EQ(windowInteriorDepth(depth, 314, 240, 8, 0.1f), 0.f);
  EXPECT_FLOAT_EQ(windowInteriorDepth(depth, 311, 240, 8, 0.1f), 2.f);  // 9 px away
  // The crate's side of the edge, a diagonal neighbour in a hole, the image border.
  EXPECT_FLOAT_EQ(windowInteriorDepth(depth, 326, 240, 8, 0.1f), 0.f);
  EXPECT_FLOAT_EQ(windowInteriorDepth(depth, 108, 108, 8, 0.1f), 0.f);
  EXPECT_FLOAT_EQ(windowInteriorDepth(depth, 5, 240, 8, 0.1f), 0.f);
  // A gentle slope (a floor) is no edge.
  cv::Mat slope(480, 640, CV_32F);
  for (int y = 0; y < 480; ++y) slope.row(y).setTo(1.f + 0.004f * y);
  EXPECT_GT(windowInteriorDepth(slope, 320, 240, 8, 0.1f), 0.f);
}

TEST(DepthCheck, AStillRoomAgreesWithAnEarlierViewAndNothingIsSeenThrough) {
  const PinholeCamera camera = cameraPreset("freiburg3");
  test::SyntheticScene scene(camera, 7);
  scene.addDefaultRoom();
  const auto before = scene.render(cameraAt(0), 0.0);
  const auto now = scene.render(cameraAt(6), 6 * kFramePeriodS);
  const DepthView view = viewOf(before, cameraAt(0), 0);
  const cv::Rect all(0, 0, camera.width, camera.height);
  const DepthAgreement a = compareWithView(now.depth_m, cv::Mat(), all, toMatx(cameraAt(6)),
                                           intrinsics(camera), view, DepthCheckOptions());
  ASSERT_GT(a.samples, 10000);
  // 12 cm and 2.4 deg apart: what both saw agrees; what only one saw is behind an occluder.
  EXPECT_GT(a.share(a.consistent), 0.97);
  EXPECT_LT(a.share(a.seen_through), 0.001);
  int regions = -1;
  const cv::Mat moved = seenThroughRegions(now.depth_m, toMatx(cameraAt(6)), intrinsics(camera),
                                           view, cv::Mat(), SeenThroughOptions(), &regions);
  EXPECT_EQ(regions, 0);
  EXPECT_EQ(cv::countNonZero(moved), 0);
}

TEST(DepthCheck, APushedBoxIsSeenThroughAndMaskedWholeWithoutTheFloor) {
  const PushedBox world;
  const auto before = world.at(0);
  const auto now = world.at(6);  // 0.2 s: the box moved 12 cm, a fifth of its width
  const DepthView view = viewOf(before, cameraAt(0), 0);
  const cv::Vec4d K = intrinsics(world.camera);
  const cv::Rect all(0, 0, world.camera.width, world.camera.height);
  const DepthAgreement box = compareWithView(now.depth_m, now.mask, all, toMatx(cameraAt(6)), K,
                                             view, DepthCheckOptions());
  ASSERT_GT(box.samples, 100);
  // Its leading fifth stands where the earlier view saw the wall behind it.
  EXPECT_GT(box.share(box.seen_through), 0.1);

  int regions = 0;
  const cv::Mat moved = seenThroughRegions(now.depth_m, toMatx(cameraAt(6)), K, view, cv::Mat(),
                                           SeenThroughOptions(), &regions);
  const int box_px = cv::countNonZero(now.mask);
  const int covered = cv::countNonZero(moved & now.mask);
  const int outside = cv::countNonZero(moved & ~now.mask);
  std::printf("box %d px: covered %d, outside %d, seen-through share %.3f\n", box_px, covered,
              outside, box.share(box.seen_through));
  EXPECT_EQ(regions, 1);
  // Grown from its seen-through part into its whole surface (depth within 15 cm) ...
  EXPECT_GT(covered, 0.9 * box_px);
  // ... and into the floor only for the few rows within that depth range of its bottom edge.
  EXPECT_LT(outside, 0.25 * box_px);
}

TEST(DepthCheck, PixelsBeyondTheMaximumDepthAreNotSampled) {
  const PushedBox world;  // the box's front face is 2.7 m away
  const auto now = world.at(6);
  const DepthView view = viewOf(world.at(0), cameraAt(0), 0);
  const cv::Vec4d K = intrinsics(world.camera);
  const cv::Rect all(0, 0, world.camera.width, world.camera.height);
  DepthCheckOptions near_only;
  near_only.max_depth_m = 2.5;
  const DepthAgreement box =
      compareWithView(now.depth_m, now.mask, all, toMatx(cameraAt(6)), K, view, near_only);
  EXPECT_EQ(box.samples, 0);
  SeenThroughOptions o;
  o.check.max_depth_m = 2.5;
  EXPECT_EQ(
      cv::countNonZero(seenThroughRegions(now.depth_m, toMatx(cameraAt(6)), K, view, cv::Mat(), o)),
      0);
  // Within the range the box is found as before.
  o.check.max_depth_m = 4.0;
  EXPECT_GT(
      cv::countNonZero(seenThroughRegions(now.depth_m, toMatx(cameraAt(6)), K, view, cv::Mat(), o) &
                       now.mask),
      0.9 * cv::countNonZero(now.mask));
}

TEST(DepthCheck, DecidedObjectsAreLeftAlone) {
  const PushedBox world;
  const auto now = world.at(6);
  const DepthView view = viewOf(world.at(0), cameraAt(0), 0);
  int regions = -1;
  const cv::Mat moved =
      seenThroughRegions(now.depth_m, toMatx(cameraAt(6)), intrinsics(world.camera), view, now.mask,
                         SeenThroughOptions(), &regions);
  EXPECT_EQ(regions, 0);
  EXPECT_EQ(cv::countNonZero(moved), 0);
}

TEST(DepthCheck, DepthStepsMarkBothSidesOfAStepButNotASlope) {
  cv::Mat depth(40, 40, CV_32F);
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 40; ++x) depth.at<float>(y, x) = 2.f + 0.005f * x;  // 5 mm a pixel
  depth(cv::Rect(20, 0, 20, 40)) += 0.1f;  // a 10 cm step between columns 19 and 20
  const cv::Mat steps = depthSteps(depth, 0.03);
  EXPECT_EQ(cv::countNonZero(steps.colRange(19, 21)), 80);
  EXPECT_EQ(cv::countNonZero(steps.colRange(0, 18)), 0);
  EXPECT_EQ(cv::countNonZero(steps.colRange(22, 40)), 0);
}

TEST(DepthCheck, GrowthStopsAtADepthStepWithABarrier) {
  // A wall 4 m away; a still block (the teddy) 1.5 m away in both frames; a chair 1.6 m away
  // that moved in beside it, touching it in the image: within the 15 cm fixed range of each
  // other, but apart by a 10 cm step.
  const cv::Rect teddy(320, 100, 120, 250), chair(200, 150, 120, 200);
  cv::Mat before(480, 640, CV_32F, cv::Scalar(4.f));
  before(teddy).setTo(1.5f);
  cv::Mat now = before.clone();
  now(chair).setTo(1.6f);
  DepthView view = DepthHistory::halfView(before, 0);
  view.T_W_C = cv::Matx44d::eye();
  const cv::Vec4d K(535.4, 539.2, 320.1, 247.6);
  SeenThroughOptions o;
  const auto grown = [&](double barrier) {
    o.barrier_step_m = barrier;
    return seenThroughRegions(now, cv::Matx44d::eye(), K, view, cv::Mat(), o);
  };
  const cv::Mat free = grown(0.0), barred = grown(0.03);
  EXPECT_GT(cv::countNonZero(free(chair)), 0.9 * chair.area());
  EXPECT_GT(cv::countNonZero(free(teddy)), 0.5 * teddy.area());  // the teddy taken along
  EXPECT_GT(cv::countNonZero(barred(chair)), 0.9 * chair.area());
  EXPECT_EQ(cv::countNonZero(barred(teddy)), 0);
}

TEST(DepthHistory, KeepsRecentViewsAndFindsTheNewestOldEnoughOne) {
  DepthHistory history(4);
  const cv::Mat depth(8, 8, CV_32FC1, cv::Scalar(1.f));
  for (long f = 0; f < 10; ++f) history.push(DepthHistory::halfView(depth, f));
  ASSERT_NE(history.newestUpTo(7), nullptr);
  EXPECT_EQ(history.newestUpTo(7)->frame, 7);
  EXPECT_EQ(history.newestUpTo(100)->frame, 9);
  ASSERT_NE(history.newestUpTo(5), nullptr);
  EXPECT_EQ(history.newestUpTo(5)->frame, 5);
  EXPECT_EQ(history.newestUpTo(5)->depth_m.size(), cv::Size(4, 4));  // half resolution
  EXPECT_EQ(history.newestUpTo(4), nullptr);  // frames older than 9 - 4 are gone
  DepthHistory off(0);
  off.push(DepthHistory::halfView(depth, 0));
  EXPECT_EQ(off.newestUpTo(0), nullptr);
}

TEST(DepthHistory, EarlierViewsFollowAPoseSnapAndAStillRoomIsSeenThroughNoMore) {
  const PinholeCamera camera = cameraPreset("freiburg3");
  test::SyntheticScene scene(camera, 7);
  scene.addDefaultRoom();
  // The tracker drifted 2 deg about the vertical before frame 6, whose pose then snapped back to
  // the truth: the view of frame 0 was kept with the drifted pose.
  const Eigen::Isometry3d drift(Eigen::AngleAxisd(2.0 * M_PI / 180.0, Eigen::Vector3d::UnitY()));
  DepthHistory history(12);
  history.push(viewOf(scene.render(cameraAt(0), 0.0), drift * cameraAt(0), 0));
  const auto now = scene.render(cameraAt(6), 6 * kFramePeriodS);
  const cv::Rect all(0, 0, camera.width, camera.height);
  const auto seenThrough = [&]() {
    const DepthAgreement a = compareWithView(now.depth_m, cv::Mat(), all, toMatx(cameraAt(6)),
                                             intrinsics(camera), *history.newestUpTo(0),
                                             DepthCheckOptions());
    return a.share(a.seen_through);
  };
  ASSERT_NE(history.newestUpTo(0), nullptr);
  const double across_the_jump = seenThrough();
  EXPECT_GT(across_the_jump, 0.01);  // the still room looks moved (a still one: < .001)
  // A refinement within 1 deg and 1 cm moves nothing.
  const Eigen::Isometry3d nudge(Eigen::AngleAxisd(0.5 * M_PI / 180.0, Eigen::Vector3d::UnitY()));
  EXPECT_FALSE(history.followPoseSnap(toMatx(nudge * cameraAt(6)), toMatx(cameraAt(6))));
  EXPECT_DOUBLE_EQ(seenThrough(), across_the_jump);
  // The snap: checked with the drifted pose, final at the truth.
  EXPECT_TRUE(history.followPoseSnap(toMatx(cameraAt(6)), toMatx(drift * cameraAt(6))));
  EXPECT_LT(seenThrough(), 0.001);
}

}  // namespace
}  // namespace dynamap
