#include <gtest/gtest.h>

#include "dynamap/mapping/static_points.hpp"
#include "synthetic_scene.hpp"

namespace dynamap::test {
namespace {

TEST(StaticPoints, DropsDilatedMaskRangeAndEdges) {
  const PinholeCamera cam = SyntheticScene::camera();
  cv::Mat depth(cam.height, cam.width, CV_32FC1, cv::Scalar(2.0f));
  depth(cv::Rect(100, 0, 60, cam.height)) = 3.0f;  // a 1 m jump at column 100
  depth.at<float>(5, 5) = 0.1f;                    // too near
  depth.at<float>(6, 6) = 5.0f;                    // too far (and an edge)
  cv::Mat mask = cv::Mat::zeros(depth.size(), CV_8UC1);
  mask(cv::Rect(40, 40, 10, 10)) = 255;
  mask(cv::Rect(10, 80, 10, 10)) = 128;  // static person: kept
  StaticPointsOptions o;
  o.mask_dilation_px = 3;
  const StaticPoints sp = extractStaticPoints(cam, cv::Mat(), depth, mask, o);
  const cv::Mat& d = sp.static_depth_m;
  EXPECT_EQ(d.at<float>(45, 45), 0.0f);  // masked
  EXPECT_EQ(d.at<float>(45, 37), 0.0f);  // within the dilation radius
  EXPECT_GT(d.at<float>(45, 35), 0.0f);  // beyond it
  EXPECT_GT(d.at<float>(85, 15), 0.0f);  // mask value 128 is static
  EXPECT_EQ(d.at<float>(5, 5), 0.0f);
  EXPECT_EQ(d.at<float>(6, 6), 0.0f);
  EXPECT_EQ(d.at<float>(60, 99), 0.0f);  // both sides of the depth edge
  EXPECT_EQ(d.at<float>(60, 100), 0.0f);
  EXPECT_GT(d.at<float>(60, 98), 0.0f);
  EXPECT_EQ(sp.points_C.size(), static_cast<std::size_t>(cv::countNonZero(d)));
  ASSERT_EQ(sp.colors.size(), sp.points_C.size());
  // Back-projection: pixel (98, 60) at 2 m.
  const Eigen::Vector3d expected = cam.backProject(98, 60, 2.0);
  bool found = false;
  for (const auto& p : sp.points_C) found = found || (p.cast<double>() - expected).norm() < 1e-5;
  EXPECT_TRUE(found);
}

TEST(StaticPoints, StrideSubsamplesPointsOnly) {
  const PinholeCamera cam = SyntheticScene::camera();
  const cv::Mat depth(cam.height, cam.width, CV_32FC1, cv::Scalar(1.5f));
  StaticPointsOptions o;
  o.stride = 4;
  const StaticPoints sp = extractStaticPoints(cam, cv::Mat(), depth, cv::Mat(), o);
  EXPECT_EQ(cv::countNonZero(sp.static_depth_m), cam.width * cam.height);
  EXPECT_EQ(sp.points_C.size(), static_cast<std::size_t>((cam.width / 4) * (cam.height / 4)));
}

TEST(StaticPoints, RejectsWrongTypes) {
  const PinholeCamera cam = SyntheticScene::camera();
  const cv::Mat depth16(cam.height, cam.width, CV_16UC1, cv::Scalar(1000));
  EXPECT_ANY_THROW(extractStaticPoints(cam, cv::Mat(), depth16, cv::Mat(), {}));
}

}  // namespace
}  // namespace dynamap::test
