// notMovers(): where the mover tracks do not look for movers (issue 50).
#include <gtest/gtest.h>

#include <algorithm>

#include <opencv2/imgproc.hpp>

#include "dynamap/core/dynamic/class_table.hpp"
#include "dynamap/core/dynamic/depth_check.hpp"
#include "dynamap/core/dynamic/mover_regions.hpp"

namespace dynamap::test {
namespace {

// A wall at 3 m; a person at 1.5 m in columns [120, 200) of rows [50, 250), and someone at
// 2.4 m in columns [70, 100).
cv::Mat personBeforeAWall() {
  cv::Mat depth(300, 400, CV_32FC1, cv::Scalar(3.0f));
  depth(cv::Rect(120, 50, 80, 200)).setTo(1.5f);
  depth(cv::Rect(70, 50, 30, 200)).setTo(2.4f);
  return depth;
}

int classIndex(const char* name) { return ClassTable::classIndex(name); }

TEST(NotMovers, ExcludeAPersonsOwnPixelsNotTheWallBehindHisBox) {
  const cv::Mat depth = personBeforeAWall();
  const ClassTable classes{DynamicConfig{}};
  // A box centred on the person, far wider than he is (the teddy taken for a person).
  const std::vector<Detection> dets{
      Detection{cv::Rect2f(60, 40, 200, 220), classIndex("person"), 0.9f}};
  const cv::Mat out = notMovers(depth, cv::Mat(), cv::Mat(), dets, classes, 0.4);
  ASSERT_EQ(out.size(), depth.size());
  EXPECT_EQ(cv::countNonZero(out(cv::Rect(120, 50, 80, 200))), 80 * 200);  // the person
  EXPECT_EQ(out.at<std::uint8_t>(150, 116), 255);                          // his 5 px margin
  EXPECT_EQ(out.at<std::uint8_t>(150, 113), 0);
  EXPECT_EQ(cv::countNonZero(out(cv::Rect(70, 50, 30, 200))), 0);   // the one behind him
  EXPECT_EQ(cv::countNonZero(out(cv::Rect(210, 50, 40, 200))), 0);  // the wall in the box
  EXPECT_EQ(cv::countNonZero(out(cv::Rect(0, 0, 400, 40))), 0);     // outside the box

  // A chair's box (not high-dynamic) excludes nothing: someone may push it.
  const std::vector<Detection> chair{
      Detection{cv::Rect2f(60, 40, 200, 220), classIndex("chair"), 0.9f}};
  EXPECT_EQ(cv::countNonZero(notMovers(depth, cv::Mat(), cv::Mat(), chair, classes, 0.4)), 0);
}

TEST(NotMovers, ExcludeAllOfAPersonsBoxWithoutDepth) {
  const cv::Mat depth(300, 400, CV_32FC1, cv::Scalar(0.0f));
  const ClassTable classes{DynamicConfig{}};
  const std::vector<Detection> dets{
      Detection{cv::Rect2f(60, 40, 200, 220), classIndex("person"), 0.9f}};
  const cv::Mat out = notMovers(depth, cv::Mat(), cv::Mat(), dets, classes, 0.4);
  EXPECT_EQ(cv::countNonZero(out), 200 * 220);
}

// A limb at another depth than its walker's body moved in beside him, and a box moved in on its
// own: with the walker's pixels given, the box is the only mover.
TEST(MoverDetections, ARegionTouchingAWalkerIsNoMover) {
  const cv::Rect person(100, 50, 80, 350), limb(180, 200, 50, 100), box(400, 250, 100, 150);
  const cv::Mat before(480, 640, CV_32F, cv::Scalar(4.f));
  cv::Mat now = before.clone();
  now(person).setTo(1.5f);
  now(limb).setTo(2.2f);
  now(box).setTo(2.0f);
  DepthView view = DepthHistory::halfView(before, 0);
  view.T_W_C = cv::Matx44d::eye();
  const cv::Vec4d K(535.4, 539.2, 320.1, 247.6);
  cv::Mat people = cv::Mat::zeros(now.size(), CV_8UC1);
  people(person).setTo(255);
  cv::Mat exclude;
  cv::dilate(people, exclude, cv::getStructuringElement(cv::MORPH_ELLIPSE, {11, 11}));
  const SeenThroughOptions o;
  const auto centres = [](const std::vector<Detection>& dets) {
    std::vector<int> x;
    for (const auto& d : dets) x.push_back(static_cast<int>(d.box.x + d.box.width / 2));
    std::sort(x.begin(), x.end());
    return x;
  };
  const std::vector<int> all =
      centres(moverDetections(now, cv::Matx44d::eye(), K, view, exclude, o));
  ASSERT_EQ(all.size(), 2u) << "the scene no longer shows what the rule is for";
  EXPECT_NEAR(all[0], 205, 10);
  const std::vector<int> apart =
      centres(moverDetections(now, cv::Matx44d::eye(), K, view, exclude, o, nullptr, people));
  ASSERT_EQ(apart.size(), 1u);
  EXPECT_NEAR(apart[0], 450, 10);
}

}  // namespace
}  // namespace dynamap::test
