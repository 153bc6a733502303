// freeSpaceViolations(): synthetic depth images of a wall 3 m away seen by a camera that moves 10
// cm sideways between keyframes, with a 40 x 40 cm box 1.5 m from the camera.
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "dynamap/mapping/free_space.hpp"

namespace dynamap {
namespace {

constexpr double kWallZ = 3.0;

struct Box {
  Eigen::Vector3d centre_W;  ///< front face centre, world frame
  double half = 0.2;
};

/// Depth seen from camera-to-world pose T_W_C: the wall z = kWallZ (world), optionally a box
/// face parallel to it (ray casting of two planes).
cv::Mat render(const PinholeCamera& cam, const Eigen::Isometry3d& T_W_C, const Box* box) {
  cv::Mat depth(480, 640, CV_32FC1);
  const Eigen::Vector3d o = T_W_C.translation();
  for (int v = 0; v < depth.rows; ++v) {
    for (int u = 0; u < depth.cols; ++u) {
      const Eigen::Vector3d ray_C = cam.backProject(u, v, 1.0);  // z = 1 in the camera
      const Eigen::Vector3d ray_W = T_W_C.rotation() * ray_C;
      double s = (kWallZ - o.z()) / ray_W.z();
      if (box != nullptr) {
        const double sb = (box->centre_W.z() - o.z()) / ray_W.z();
        const Eigen::Vector3d p = o + sb * ray_W;
        if (std::abs(p.x() - box->centre_W.x()) < box->half &&
            std::abs(p.y() - box->centre_W.y()) < box->half) {
          s = sb;
        }
      }
      depth.at<float>(v, u) = static_cast<float>(s);  // camera z of the hit (ray_C.z() == 1)
    }
  }
  return depth;
}

Eigen::Isometry3d poseAt(double x) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(x, 0.0, 0.0);
  return T;
}

/// Flags of the view (depth, pose) against the given other views.
cv::Mat flags(const PinholeCamera& cam, const cv::Mat& depth, const Eigen::Isometry3d& T,
              const std::vector<FreeSpaceView>& others) {
  std::vector<const FreeSpaceView*> ptrs;
  for (const auto& o : others) ptrs.push_back(&o);
  return freeSpaceViolations(cam, depth, T, ptrs, FreeSpaceOptions{});
}

double share(const cv::Mat& mask, const cv::Rect& roi) {
  return cv::countNonZero(mask(roi)) / static_cast<double>(roi.area());
}

/// Image rectangle of the box face seen from pose x (camera looks along +z, no rotation).
cv::Rect boxRect(const PinholeCamera& cam, const Box& b, double x) {
  const double z = b.centre_W.z();
  const int u0 = static_cast<int>(cam.fx * (b.centre_W.x() - b.half - x) / z + cam.cx);
  const int u1 = static_cast<int>(cam.fx * (b.centre_W.x() + b.half - x) / z + cam.cx);
  const int v0 = static_cast<int>(cam.fy * (b.centre_W.y() - b.half) / z + cam.cy);
  const int v1 = static_cast<int>(cam.fy * (b.centre_W.y() + b.half) / z + cam.cy);
  return cv::Rect(cv::Point(u0, v0), cv::Point(u1, v1)) & cv::Rect(0, 0, 640, 480);
}

TEST(FreeSpace, StaticSceneWithCameraMotionFlagsNothing) {
  const PinholeCamera cam;
  const Box still{Eigen::Vector3d(0.0, 0.0, 1.5)};
  std::vector<FreeSpaceView> views;
  std::vector<cv::Mat> depths;
  for (int k = 0; k < 4; ++k) {
    depths.push_back(render(cam, poseAt(0.1 * k), &still));
    views.push_back(makeFreeSpaceView(depths.back(), poseAt(0.1 * k)));
  }
  for (int k = 0; k < 4; ++k) {
    std::vector<FreeSpaceView> others = views;
    others.erase(others.begin() + k);
    const cv::Mat moved = flags(cam, depths[k], poseAt(0.1 * k), others);
    ASSERT_EQ(moved.size(), cv::Size(640, 480));
    // Depth edges of the box (disocclusions as the camera moves) must not count.
    EXPECT_EQ(cv::countNonZero(moved), 0) << "keyframe " << k;
  }
}

// The box moves from x = -0.5 to x = 0.3 between two keyframes: each keyframe's box lies in
// space that the other keyframe saw free (moved in / moved out); nothing else is flagged.
TEST(FreeSpace, ObjectThatMovedIsFlaggedInEarlierAndLaterKeyframes) {
  const PinholeCamera cam;
  const Box before{Eigen::Vector3d(-0.5, 0.0, 1.5)};
  const Box after{Eigen::Vector3d(0.3, 0.0, 1.5)};
  const cv::Mat d0 = render(cam, poseAt(0.0), &before);
  const cv::Mat d1 = render(cam, poseAt(0.1), &after);
  const FreeSpaceView v0 = makeFreeSpaceView(d0, poseAt(0.0));
  const FreeSpaceView v1 = makeFreeSpaceView(d1, poseAt(0.1));
  const struct {
    cv::Mat depth;
    double x;
    const Box* box;
    const FreeSpaceView* other;
  } cases[] = {{d1, 0.1, &after, &v0}, {d0, 0.0, &before, &v1}};
  for (const auto& c : cases) {
    const cv::Mat moved = flags(cam, c.depth, poseAt(c.x), {*c.other});
    // The box: flagged (5 % tolerance for its border).
    EXPECT_GT(share(moved, boxRect(cam, *c.box, c.x)), 0.95) << "keyframe at x = " << c.x;
    // The rest, including where the box is in the other keyframe (a disocclusion): nothing.
    cv::Mat rest = moved.clone();
    rest(boxRect(cam, *c.box, c.x)).setTo(0);
    EXPECT_LT(cv::countNonZero(rest), 0.002 * 640 * 480) << "keyframe at x = " << c.x;
  }
}

// A small moved object (6 x 6 cm, ~450 px, below min_area_px) counts as noise on its own, but
// is kept when it lies within fringe_px of the keyframe's mask: the rim of a masked mover.
TEST(FreeSpace, SmallRegionIsKeptOnlyNextToTheMask) {
  const PinholeCamera cam;
  const Box before{Eigen::Vector3d(-0.5, 0.0, 1.5), 0.03};
  const Box after{Eigen::Vector3d(0.3, 0.0, 1.5), 0.03};
  const FreeSpaceView v0 = makeFreeSpaceView(render(cam, poseAt(0.0), &before), poseAt(0.0));
  const cv::Mat d1 = render(cam, poseAt(0.1), &after);
  const cv::Rect rim = boxRect(cam, after, 0.1);
  ASSERT_LT(rim.area(), FreeSpaceOptions{}.min_area_px);
  const std::vector<const FreeSpaceView*> others{&v0};
  EXPECT_EQ(cv::countNonZero(freeSpaceViolations(cam, d1, poseAt(0.1), others, {})), 0);
  cv::Mat mask = cv::Mat::zeros(d1.size(), CV_8UC1);
  mask(cv::Rect(rim.x - 60, rim.y, 56, rim.height)).setTo(255);  // ends 4 px left of the rim
  FreeSpaceOptions fringe;
  fringe.fringe_px = 12;
  const cv::Mat near = freeSpaceViolations(cam, d1, poseAt(0.1), others, fringe, mask);
  EXPECT_GT(share(near, rim), 0.8);
  EXPECT_EQ(cv::countNonZero(near(cv::Rect(0, 0, rim.x - 4, 480))), 0);  // the mask itself
  FreeSpaceOptions no_fringe;
  no_fringe.fringe_px = 0;
  EXPECT_EQ(cv::countNonZero(freeSpaceViolations(cam, d1, poseAt(0.1), others, no_fringe, mask)),
            0);
}

TEST(FreeSpace, SmallPoseErrorAndDepthNoiseFlagNothing) {
  const PinholeCamera cam;
  const Box still{Eigen::Vector3d(0.0, 0.0, 1.5)};
  const FreeSpaceView v0 = makeFreeSpaceView(render(cam, poseAt(0.0), &still), poseAt(0.0));
  cv::Mat depth = render(cam, poseAt(0.1), &still);
  cv::Mat noise(depth.size(), CV_32FC1);
  cv::randn(noise, 0.0, 0.01);  // 1 cm
  depth += noise;
  Eigen::Isometry3d wrong = poseAt(0.1);
  wrong.translation() += Eigen::Vector3d(0.01, -0.01, 0.02);  // 2.4 cm pose error
  wrong.rotate(Eigen::AngleAxisd(0.005, Eigen::Vector3d::UnitY()));
  EXPECT_EQ(cv::countNonZero(flags(cam, depth, wrong, {v0})), 0);
}

}  // namespace
}  // namespace dynamap
