#include <gtest/gtest.h>

#include "dynamap/core/dynamic/depth_check.hpp"
#include "dynamap/core/dynamic/region_fusion.hpp"
#include "dynamap/core/dynamic/support_planes.hpp"

namespace dynamap::support_planes_test {
namespace {

// A camera 0.8 m above a floor, looking level at a wall 4 m away; a person (a flat board,
// 1.7 m tall) stands on the floor 2.5 m away. Depth with the Kinect's noise.
constexpr double kFx = 540.0, kCx = 320.0, kCy = 240.0, kHeightM = 0.8, kPersonM = 2.5;
const cv::Vec4d kK(kFx, kFx, kCx, kCy);

struct FloorScene {
  cv::Mat depth = cv::Mat(480, 640, CV_32F);
  cv::Mat floor = cv::Mat::zeros(480, 640, CV_8UC1), person = cv::Mat::zeros(480, 640, CV_8UC1);
  cv::Rect detection;

  FloorScene() {
    const int feet = static_cast<int>(kCy + kHeightM * kFx / kPersonM);          // row 412
    const int head = static_cast<int>(kCy - (1.7 - kHeightM) * kFx / kPersonM);  // row 45
    cv::RNG rng(3);
    for (int v = 0; v < depth.rows; ++v) {
      // Rows below the horizon see the floor up to the wall's foot.
      const double z_floor = v > kCy ? kHeightM * kFx / (v - kCy) : 1e9;
      for (int u = 0; u < depth.cols; ++u) {
        double z = std::min(z_floor, 4.0);
        if (z_floor < 4.0) floor.at<uchar>(v, u) = 255;
        if (u >= 290 && u < 350 && v >= head && v <= feet) {
          z = kPersonM, person.at<uchar>(v, u) = 255, floor.at<uchar>(v, u) = 0;
        }
        depth.at<float>(v, u) = static_cast<float>(z + rng.gaussian(depthNoiseM(z)));
      }
    }
    detection = cv::Rect(275, head - 15, 90, feet - head + 30);  // a detector's loose box
  }
};

double share(const cv::Mat& of, const cv::Mat& in) {
  return cv::countNonZero(of & in) / static_cast<double>(cv::countNonZero(in));
}

double iou(const cv::Mat& a, const cv::Mat& b) {
  return cv::countNonZero(a & b) / static_cast<double>(cv::countNonZero(a | b));
}

TEST(SupportPlanes, FindTheFloorAndTheWallBesideAPerson) {
  FloorScene s;
  cv::Mat exclude = cv::Mat::zeros(s.depth.size(), CV_8UC1);
  exclude(s.detection).setTo(255);
  const SupportPlaneOptions o;
  const std::vector<Plane> planes = findSupportPlanes(s.depth, kK, exclude, o);
  ASSERT_EQ(planes.size(), 2u);
  bool floor = false, wall = false;
  for (const auto& p : planes) {
    // Floor: normal along y, 0.8 m from the camera (within 2.5 degrees and 4 cm: the noise
    // grows with depth on the grazing floor); wall: along z, 4 m (1 degree, 2 cm).
    floor = floor || (std::abs(p.n[1]) > 0.999 && std::abs(std::abs(p.d) - kHeightM) < 0.04);
    wall = wall || (std::abs(p.n[2]) > 0.9998 && std::abs(std::abs(p.d) - 4.0) < 0.02);
  }
  EXPECT_TRUE(floor);
  EXPECT_TRUE(wall);
  const cv::Mat on = planePixels(s.depth, kK, planes, o);
  EXPECT_GT(share(on, s.floor), 0.95);
  EXPECT_LT(share(on, s.person), 0.03);  // the rows of the feet within the 4 cm margin
}

TEST(SupportPlanes, TheFloorAtAPersonsFeetIsNotThePersons) {
  FloorScene s;
  double mode = 0.0;
  const cv::Mat plain = objectPixels(s.depth, s.detection, 0.4, &mode);
  // The depth cut alone takes the floor around the feet (same depth as the person).
  EXPECT_GT(cv::countNonZero(plain & s.floor), 1000);
  cv::Mat exclude = cv::Mat::zeros(s.depth.size(), CV_8UC1);
  exclude(s.detection).setTo(255);
  const SupportPlaneOptions o;
  const cv::Mat on = planePixels(s.depth, kK, findSupportPlanes(s.depth, kK, exclude, o), o);
  const cv::Mat cut = objectPixels(s.depth, s.detection, 0.4, &mode, 0.0, on);
  EXPECT_NEAR(mode, kPersonM, 0.05);
  EXPECT_LT(cv::countNonZero(cut & s.floor), 200);
  EXPECT_GT(iou(cut, s.person), 0.95);
  // A box that holds only floor owns nothing (an all-zero mask, not "no depth").
  const cv::Mat floor_only = objectPixels(s.depth, cv::Rect(40, 380, 120, 90), 0.4, &mode, 0.0, on);
  ASSERT_FALSE(floor_only.empty());
  EXPECT_EQ(cv::countNonZero(floor_only), 0);
}

TEST(SupportPlanes, NoPlaneInAFrameOfClutter) {
  // Random depths: no plane holds 15 % of the samples.
  cv::Mat depth(480, 640, CV_32F);
  cv::RNG rng(5);
  rng.fill(depth, cv::RNG::UNIFORM, 0.5, 5.0);
  EXPECT_TRUE(findSupportPlanes(depth, kK, cv::Mat(), SupportPlaneOptions()).empty());
}

}  // namespace
}  // namespace dynamap::support_planes_test
