// What of a view the keyframes near it already saw outside their movers (view_coverage.hpp):
// the test of revisits for a new keyframe.
#include <gtest/gtest.h>

#include "dynamap/core/camera.hpp"
#include "dynamap/core/tracking/view_coverage.hpp"

namespace dynamap {
namespace {

/// A frame looking at a wall 2 m away, no movers, at pose T_W_C.
struct WallFrame {
  PinholeCamera camera = cameraPreset("freiburg3");
  cv::Mat depth_m = cv::Mat(480, 640, CV_32F, cv::Scalar(2.0f));
  cv::Mat movers;
  CoverageQuery query(const Eigen::Isometry3d& T_W_C = Eigen::Isometry3d::Identity()) const {
    CoverageQuery q;
    q.camera = &camera;
    q.depth_m = &depth_m;
    q.movers = &movers;
    q.T_W_C = T_W_C;
    return q;
  }
};

cv::Mat leftHalfMoving() {
  cv::Mat m(480, 640, CV_8U, cv::Scalar(0));
  m.colRange(0, 320).setTo(255);
  return m;
}

TEST(ViewCoverage, StaticCellsMarkWhatLiesMostlyOutsideTheMovers) {
  const cv::Mat cells = staticCells(leftHalfMoving(), 640, 480);
  ASSERT_EQ(cells.cols, 40);
  ASSERT_EQ(cells.rows, 30);
  EXPECT_EQ(cv::countNonZero(cells.colRange(0, 20)), 0);
  EXPECT_EQ(cv::countNonZero(cells.colRange(20, 40)), 20 * 30);
  EXPECT_EQ(cv::countNonZero(staticCells(cv::Mat(), 640, 480)), 40 * 30);  // no movers
}

TEST(ViewCoverage, TheSameViewIsCoveredAndAViewElsewhereIsNot) {
  const WallFrame frame;
  const CoverageView same{Eigen::Isometry3d::Identity(), staticCells(cv::Mat(), 640, 480)};
  EXPECT_EQ(uncoveredShare(frame.query(), {same}), 0.0);
  Eigen::Isometry3d turned = Eigen::Isometry3d::Identity();
  turned.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix();
  EXPECT_EQ(uncoveredShare(frame.query(), {CoverageView{turned, cv::Mat()}}), 1.0);
  EXPECT_EQ(uncoveredShare(frame.query(), {}), 1.0);
}

TEST(ViewCoverage, WhatAKeyframeHadMaskedIsUncoveredUnlessAnotherSawIt) {
  WallFrame frame;
  const CoverageView masked{Eigen::Isometry3d::Identity(), staticCells(leftHalfMoving(), 640, 480)};
  // Half the wall was behind a mover in the keyframe: a new keyframe adds it (tolerance: one
  // column of cells).
  EXPECT_NEAR(uncoveredShare(frame.query(), {masked}), 0.5, 1.0 / 40);
  const CoverageView clear{Eigen::Isometry3d::Identity(), cv::Mat()};
  EXPECT_EQ(uncoveredShare(frame.query(), {masked, clear}), 0.0);
  // The same mover in the frame too: what the frame shows static, the keyframe saw.
  frame.movers = leftHalfMoving();
  EXPECT_NEAR(uncoveredShare(frame.query(), {masked}), 0.0, 1.0 / 40);
}

TEST(ViewCoverage, AFrameWithoutDepthAddsNothing) {
  WallFrame frame;
  frame.depth_m.setTo(0.0f);
  EXPECT_EQ(uncoveredShare(frame.query(), {}), 0.0);
}

}  // namespace
}  // namespace dynamap
