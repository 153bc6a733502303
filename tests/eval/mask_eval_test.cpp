#include "mask_eval.hpp"

#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

namespace dynamap {
namespace {

TEST(MaskEval, IouAndStandingShareOnKnownRectangles) {
  cv::Mat gt = cv::Mat::zeros(100, 100, CV_8UC1);
  gt(cv::Rect(0, 0, 20, 50)).setTo(255);    // moving person: 1000 px
  gt(cv::Rect(60, 0, 10, 40)).setTo(128);   // standing person: 400 px
  cv::Mat est = cv::Mat::zeros(100, 100, CV_8UC1);
  est(cv::Rect(10, 0, 20, 50)).setTo(255);  // half overlaps the mover: 500 of 1000
  est(cv::Rect(60, 0, 10, 10)).setTo(255);  // 100 px of the standing person
  est(cv::Rect(90, 90, 5, 5)).setTo(128);   // not 255: static
  const MaskFrameScore s = scoreMask(est, gt);
  EXPECT_EQ(s.gt_moving, 1000u);
  EXPECT_EQ(s.est_dynamic, 1100u);
  EXPECT_EQ(s.intersection, 500u);
  EXPECT_NEAR(s.iou(), 500.0 / 1600.0, 1e-12);
  MaskScoreSummary summary;
  summary.add(s);
  summary.add(scoreMask(cv::Mat(), cv::Mat::zeros(100, 100, CV_8UC1)));  // nothing anywhere
  EXPECT_EQ(summary.frames(), 2u);
  EXPECT_EQ(summary.framesWithMoving(), 1u);
  EXPECT_NEAR(summary.meanIou(), 500.0 / 1600.0, 1e-12);
  EXPECT_NEAR(summary.standingMaskedShare(), 100.0 / 400.0, 1e-12);
  EXPECT_NEAR(summary.pixelRecall(), 0.5, 1e-12);
  EXPECT_NE(summary.toJson().find("\"mean_iou\""), std::string::npos);
}

TEST(MaskEval, SizeMismatchIsAnError) {
  EXPECT_THROW(scoreMask(cv::Mat::zeros(10, 10, CV_8UC1), cv::Mat::zeros(20, 20, CV_8UC1)),
               std::invalid_argument);
}

}  // namespace
}  // namespace dynamap
