#include <cmath>

#include <gtest/gtest.h>

#include "dynamap/core/tracking/depth_alignment.hpp"
#include "synthetic_scene.hpp"

namespace dynamap {
namespace {

PinholeCamera testCamera() {
  PinholeCamera camera;
  camera.width = 640;
  camera.height = 480;
  return camera;
}

double angleDeg(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() * 180.0 / M_PI;
}

PosedDepth posed(const test::RenderedFrame& f, const Eigen::Isometry3d& T_W_C, bool masked) {
  PosedDepth d;
  d.depth_m = f.depth_m;
  if (masked) d.moving_mask = f.mask;
  d.T_W_C = T_W_C;
  return d;
}

// Tolerances: 5 mm and 0.3 degrees, a tenth of the motion between the two views.
TEST(DepthAlignment, FindsTheMotionInARoomFromTheLastPose) {
  const PinholeCamera camera = testCamera();
  test::SyntheticScene scene(camera, 3);
  scene.addDefaultRoom();
  const Eigen::Isometry3d T_ref = test::cameraPose({0.0, 0.0, 0.0}, 0.0, 0.0);
  const Eigen::Isometry3d T_cur = test::cameraPose({0.04, -0.02, 0.05}, 2.5, -1.5);
  const PosedDepth ref = posed(scene.render(T_ref, 0.0), T_ref, false);
  PosedDepth cur = posed(scene.render(T_cur, 0.0), T_ref, false);  // guess: the last pose
  const DepthAlignment a = alignDepth(ref, cur, camera);
  EXPECT_TRUE(a.accepted) << a.inliers << " inliers, weakest direction " << a.weakest_direction_points;
  EXPECT_LT((a.T_W_C.translation() - T_cur.translation()).norm(), 0.005);
  EXPECT_LT(angleDeg(a.T_W_C, T_cur), 0.3);
  EXPECT_LT(a.rms_m, 0.002);
}

TEST(DepthAlignment, AMaskedMoverCoveringMuchOfTheViewDoesNotPullThePose) {
  const PinholeCamera camera = testCamera();
  test::SyntheticScene scene(camera, 5);
  scene.addDefaultRoom();
  // Left of centre: the right static box's side (the view's only x-facing surface) stays seen.
  scene.addMovingBox({-0.5, 0.2, 1.5}, {0.4, 0.8, 0.15}, {0.8, 0.0, 0.0});
  const Eigen::Isometry3d T_ref = test::cameraPose({0.0, 0.0, 0.0}, 0.0, 0.0);
  const Eigen::Isometry3d T_cur = test::cameraPose({-0.03, 0.01, 0.03}, -2.0, 1.0);
  const test::RenderedFrame f_ref = scene.render(T_ref, 0.0), f_cur = scene.render(T_cur, 0.1);
  ASSERT_GT(cv::countNonZero(f_cur.mask), f_cur.mask.total() / 4);  // the box fills > 25 %
  const DepthAlignment a =
      alignDepth(posed(f_ref, T_ref, true), posed(f_cur, T_ref, true), camera);
  EXPECT_TRUE(a.accepted) << a.inliers << " inliers (" << a.inlier_share << "), weakest direction "
                          << a.weakest_direction_points << ", rms " << a.rms_m;
  EXPECT_LT((a.T_W_C.translation() - T_cur.translation()).norm(), 0.005);
  EXPECT_LT(angleDeg(a.T_W_C, T_cur), 0.3);
}

TEST(DepthAlignment, OnePlaneLeavesTranslationFreeAndIsNotAccepted) {
  const PinholeCamera camera = testCamera();
  test::SyntheticScene scene(camera, 7);
  scene.addPlane({-4.0, -3.0, 2.5}, {8.0, 0, 0}, {0, 6.0, 0});  // a wall filling the view
  const Eigen::Isometry3d T_ref = Eigen::Isometry3d::Identity();
  const Eigen::Isometry3d T_cur = test::cameraPose({0.05, 0.0, 0.02}, 0.0, 0.0);
  const DepthAlignment a = alignDepth(posed(scene.render(T_ref, 0.0), T_ref, false),
                                      posed(scene.render(T_cur, 0.0), T_ref, false), camera);
  EXPECT_FALSE(a.accepted) << "weakest direction " << a.weakest_direction_points;
  EXPECT_LT(a.weakest_direction_points, 1.0);
}

TEST(DepthAlignment, NoDepthIsNotAccepted) {
  const PinholeCamera camera = testCamera();
  PosedDepth empty;
  empty.depth_m = cv::Mat::zeros(480, 640, CV_32FC1);
  EXPECT_FALSE(alignDepth(empty, empty, camera).accepted);
}

}  // namespace
}  // namespace dynamap
