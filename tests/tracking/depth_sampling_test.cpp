// sampleDepth() (core/include/dynamap/core/tracking/depth_sampling.hpp): the nearest pixel's
// depth, or 0 for missing readings, the image edge, the depth range and depth discontinuities.
#include <gtest/gtest.h>

#include <limits>

#include "dynamap/core/tracking/depth_sampling.hpp"

namespace dynamap {
namespace {

constexpr double kMin = 0.1, kMax = 6.0;

/// 40 x 30 depth image of a slanted plane: 2 m at x = 0, +1 mm per column (a 3x3 neighbourhood
/// spans 2 mm, far below the discontinuity bound of 4 % of the depth + 1 cm).
cv::Mat slantedPlane() {
  cv::Mat d(30, 40, CV_32FC1);
  for (int y = 0; y < d.rows; ++y) {
    for (int x = 0; x < d.cols; ++x) d.at<float>(y, x) = 2.0f + 0.001f * static_cast<float>(x);
  }
  return d;
}

TEST(DepthSampling, ReturnsTheNearestPixelsDepth) {
  const cv::Mat d = slantedPlane();
  EXPECT_FLOAT_EQ(sampleDepth(d, 10.f, 12.f, kMin, kMax), 2.010f);
  EXPECT_FLOAT_EQ(sampleDepth(d, 10.49f, 12.4f, kMin, kMax), 2.010f);
  EXPECT_FLOAT_EQ(sampleDepth(d, 10.5f, 12.f, kMin, kMax), 2.011f);  // halves round away
  EXPECT_FLOAT_EQ(sampleDepth(d, 9.6f, 11.6f, kMin, kMax), 2.010f);
}

TEST(DepthSampling, MissingReadingsGiveZero) {
  cv::Mat d = slantedPlane();
  d.at<float>(12, 10) = 0.f;  // the pixel itself
  EXPECT_EQ(sampleDepth(d, 10.f, 12.f, kMin, kMax), 0.0);
  d = slantedPlane();
  d.at<float>(13, 11) = 0.f;  // one of its 8 neighbours
  EXPECT_EQ(sampleDepth(d, 10.f, 12.f, kMin, kMax), 0.0);
  EXPECT_GT(sampleDepth(d, 8.f, 12.f, kMin, kMax), 0.0);  // two columns away: untouched
  d = slantedPlane();
  d.at<float>(11, 9) = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(sampleDepth(d, 10.f, 12.f, kMin, kMax), 0.0);
  d = slantedPlane();
  d.at<float>(12, 10) = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(sampleDepth(d, 10.f, 12.f, kMin, kMax), 0.0);
}

TEST(DepthSampling, ImageEdgeEmptyAndWrongTypeGiveZero) {
  const cv::Mat d = slantedPlane();
  // The 3x3 neighbourhood must fit: rows/columns 0 and last give 0, 1 and last-1 do not.
  EXPECT_EQ(sampleDepth(d, 0.f, 12.f, kMin, kMax), 0.0);
  EXPECT_EQ(sampleDepth(d, 39.f, 12.f, kMin, kMax), 0.0);
  EXPECT_EQ(sampleDepth(d, 10.f, 0.f, kMin, kMax), 0.0);
  EXPECT_EQ(sampleDepth(d, 10.f, 29.f, kMin, kMax), 0.0);
  EXPECT_EQ(sampleDepth(d, 38.6f, 12.f, kMin, kMax), 0.0);  // rounds to column 39
  EXPECT_EQ(sampleDepth(d, -5.f, -5.f, kMin, kMax), 0.0);
  EXPECT_EQ(sampleDepth(d, 400.f, 12.f, kMin, kMax), 0.0);
  EXPECT_GT(sampleDepth(d, 1.f, 1.f, kMin, kMax), 0.0);
  EXPECT_GT(sampleDepth(d, 38.f, 28.f, kMin, kMax), 0.0);
  EXPECT_EQ(sampleDepth(cv::Mat(), 10.f, 12.f, kMin, kMax), 0.0);
  cv::Mat mm;
  d.convertTo(mm, CV_16UC1, 1000.0);  // millimetres: not the documented CV_32FC1 metres
  EXPECT_EQ(sampleDepth(mm, 10.f, 12.f, kMin, kMax), 0.0);
}

TEST(DepthSampling, DepthOutsideTheRangeGivesZero) {
  const cv::Mat d = slantedPlane();  // 2.000 - 2.039 m
  EXPECT_EQ(sampleDepth(d, 10.f, 12.f, kMin, 1.5), 0.0);
  EXPECT_EQ(sampleDepth(d, 10.f, 12.f, 2.5, kMax), 0.0);
  // The bounds are inclusive.
  const double z = d.at<float>(12, 10);
  EXPECT_EQ(sampleDepth(d, 10.f, 12.f, z, z), z);
}

TEST(DepthSampling, DiscontinuitiesGiveZeroAndGentleSlopesDoNot) {
  // Bound at 2 m: 0.04 * 2 + 0.01 = 9 cm of spread in the 3x3 neighbourhood.
  cv::Mat flat(30, 40, CV_32FC1, cv::Scalar(2.0f));
  cv::Mat d = flat.clone();
  d.at<float>(11, 11) = 2.085f;  // 8.5 cm: a steep surface, kept
  EXPECT_FLOAT_EQ(sampleDepth(d, 10.f, 12.f, kMin, kMax), 2.0f);
  d.at<float>(11, 11) = 2.095f;  // 9.5 cm: a discontinuity
  EXPECT_EQ(sampleDepth(d, 10.f, 12.f, kMin, kMax), 0.0);
  d.at<float>(11, 11) = 1.5f;  // a nearer object's edge beside the pixel
  EXPECT_EQ(sampleDepth(d, 10.f, 12.f, kMin, kMax), 0.0);
  // One pixel farther from that edge the neighbourhood is flat again.
  EXPECT_FLOAT_EQ(sampleDepth(d, 8.f, 12.f, kMin, kMax), 2.0f);
  // An occluding edge along a column: both sides within one pixel of it give 0.
  d = flat.clone();
  d.colRange(20, 40).setTo(3.0f);
  EXPECT_EQ(sampleDepth(d, 19.f, 12.f, kMin, kMax), 0.0);
  EXPECT_EQ(sampleDepth(d, 20.f, 12.f, kMin, kMax), 0.0);
  EXPECT_FLOAT_EQ(sampleDepth(d, 18.f, 12.f, kMin, kMax), 2.0f);
  EXPECT_FLOAT_EQ(sampleDepth(d, 21.f, 12.f, kMin, kMax), 3.0f);
}

}  // namespace
}  // namespace dynamap
