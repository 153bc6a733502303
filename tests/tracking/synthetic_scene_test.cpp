#include <gtest/gtest.h>

#include <chrono>

#include "synthetic_scene.hpp"

namespace dynamap {
namespace {

TEST(SyntheticScene, DepthColourAndMaskMatchTheGeometry) {
  const PinholeCamera camera = cameraPreset("freiburg3");
  test::SyntheticScene scene(camera, 3);
  scene.addPlane({-2.0, -1.5, 3.0}, {4.0, 0, 0}, {0, 3.0, 0});  // fronto-parallel at z = 3 m
  scene.addMovingBox({0.0, 0.0, 2.0}, {0.2, 0.2, 0.2}, {0.5, 0.0, 0.0});
  const auto f0 = scene.render(Eigen::Isometry3d::Identity(), 0.0);
  // The box's front face (z = 1.8 m) covers the principal point; the wall is visible elsewhere.
  const int cx = static_cast<int>(camera.cx), cy = static_cast<int>(camera.cy);
  EXPECT_NEAR(f0.depth_m.at<float>(cy, cx), 1.8f, 1e-4f);
  EXPECT_EQ(f0.mask.at<std::uint8_t>(cy, cx), 255);
  EXPECT_NEAR(f0.depth_m.at<float>(20, 20), 3.0f, 1e-4f);
  EXPECT_EQ(f0.mask.at<std::uint8_t>(20, 20), 0);
  // Box half-width 0.2 m at 1.8 m: about 2 * 0.2 / 1.8 * fx pixels wide.
  const int width_px = cv::countNonZero(f0.mask.row(cy));
  EXPECT_NEAR(width_px, 2 * 0.2 / 1.8 * camera.fx, 3.0);
  // One second later the box moved 0.5 m to the right: the right edge of its front face (the
  // side faces it uncovers are on the left) moves by 0.5 / 1.8 * fx pixels.
  const auto f1 = scene.render(Eigen::Isometry3d::Identity(), 1.0);
  auto rightEdge = [&](const cv::Mat& mask) {
    int right = -1;
    for (int x = 0; x < mask.cols; ++x) {
      if (mask.at<std::uint8_t>(cy, x) == 255) right = x;
    }
    return right;
  };
  EXPECT_NEAR(rightEdge(f1.mask) - rightEdge(f0.mask), 0.5 / 1.8 * camera.fx, 2.0);
  // Rich texture: plenty of colour variation for ORB / LK.
  cv::Scalar mean, stddev;
  cv::meanStdDev(f0.bgr, mean, stddev);
  EXPECT_GT(stddev[1], 30.0);
}

TEST(SyntheticScene, RendersQuickly) {
  const PinholeCamera camera = cameraPreset("freiburg3");
  test::SyntheticScene scene(camera, 4);
  scene.addDefaultRoom();
  const auto start = std::chrono::steady_clock::now();
  constexpr int kFrames = 10;
  for (int i = 0; i < kFrames; ++i) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation().x() = 0.01 * i;
    scene.render(T, 0.0);
  }
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count() /
      kFrames;
  std::cout << "[synthetic scene] " << ms << " ms per 640x480 frame\n";
  EXPECT_LT(ms, 100.0);  // ~10-20 ms on an idle 2-core machine; loose for shared CI machines
}

}  // namespace
}  // namespace dynamap
