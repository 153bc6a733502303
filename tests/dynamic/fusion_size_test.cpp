#include <gtest/gtest.h>

#include "dynamap/core/dynamic/region_fusion.hpp"
#include "mask_share.hpp"

namespace dynamap {
namespace {

// A walker cut by the right image border: the detector's box (300 px tall) holds a sliver of
// him at 2.5 m and, in its centre, the wall 5 m away. A person 300 px tall at 5 m would be
// 300 * 5 / 540 = 2.8 m tall: the wall is not the person.
struct BorderScene {
  cv::Mat depth = cv::Mat(480, 640, CV_32F, cv::Scalar(5.f));
  cv::Rect walker{600, 100, 32, 300};  // visible part; the sensor's blind band beyond
  cv::Rect box{520, 100, 120, 300};
  std::vector<cv::Point2f> points;
  std::vector<std::uint8_t> dynamic;
  FusionEvidence evidence;

  BorderScene() {
    depth(walker).setTo(2.5f);
    depth(cv::Rect(632, 0, 8, 480)).setTo(0.f);
    for (int y = 5; y < 480; y += 10) {
      for (int x = 5; x < 640; x += 10) {
        points.emplace_back(static_cast<float>(x), static_cast<float>(y));
        dynamic.push_back(walker.contains({x, y}) ? 1 : 0);
      }
    }
    evidence.K = cv::Vec4d(540.0, 540.0, 320.0, 240.0);
  }
};

using test::maskedShare;

TEST(PersonSize, ObjectPixelsIgnoreDepthBeyondTheBound) {
  BorderScene s;
  double mode = 0.0;
  // Unbounded, the box centre's dominant depth wins: the wall.
  const cv::Mat wall = objectPixels(s.depth, s.box, 0.4, &mode);
  EXPECT_NEAR(mode, 5.0, 0.1);
  EXPECT_GT(maskedShare(wall, cv::Rect(530, 110, 60, 280)), 0.95);
  // Bounded at 2.5 m x 540 / 300 = 4.5 m: the walker, and no wall.
  const cv::Mat walker = objectPixels(s.depth, s.box, 0.4, &mode, 0.0, cv::Mat(), false, 4.5);
  EXPECT_NEAR(mode, 2.5, 0.1);
  EXPECT_GT(maskedShare(walker, s.walker), 0.95);
  EXPECT_EQ(cv::countNonZero(walker(cv::Rect(520, 100, 75, 300))), 0);
  // A prior on the wall (the track took it a frame ago) does not hold against the bound.
  const cv::Mat held = objectPixels(s.depth, s.box, 0.4, &mode, 5.0, cv::Mat(), false, 4.5);
  EXPECT_NEAR(mode, 2.5, 0.1);
  EXPECT_EQ(cv::countNonZero(held(cv::Rect(520, 100, 75, 300))), 0);
  // Only depth beyond the bound (the walker gone): nothing, not the whole box.
  cv::Mat gone = s.depth.clone();
  gone(s.walker).setTo(5.f);
  const cv::Mat none = objectPixels(gone, s.box, 0.4, &mode, 0.0, cv::Mat(), false, 4.5);
  ASSERT_FALSE(none.empty());
  EXPECT_EQ(cv::countNonZero(none), 0);
}

TEST(PersonSize, FusionMasksTheWalkerNotTheWallBesideHim) {
  BorderScene s;
  const std::vector<Detection> person{{cv::Rect2f(s.box), 0, 0.9f}};
  DynamicConfig c;
  RegionFusion bounded(c, ClassTable(c));
  const FusionResult r =
      bounded.fuse(FusionMode::kBoth, s.depth, s.points, s.dynamic, person, s.evidence);
  EXPECT_GT(maskedShare(r.mask, s.walker), 0.95);
  EXPECT_LT(maskedShare(r.mask, cv::Rect(530, 110, 60, 280)), 0.01);

  c.person_max_height_m = 0.0;  // off: the box's depth cut is the wall
  RegionFusion unbounded(c, ClassTable(c));
  const FusionResult u =
      unbounded.fuse(FusionMode::kBoth, s.depth, s.points, s.dynamic, person, s.evidence);
  EXPECT_GT(maskedShare(u.mask, cv::Rect(530, 110, 60, 280)), 0.95);

  // The bound is a person's: a car's box over the same depth still takes the wall.
  const std::vector<Detection> car{{cv::Rect2f(s.box), ClassTable::classIndex("car"), 0.9f}};
  RegionFusion other(DynamicConfig{}, ClassTable(DynamicConfig{}));
  const FusionResult o =
      other.fuse(FusionMode::kBoth, s.depth, s.points, s.dynamic, car, s.evidence);
  EXPECT_GT(maskedShare(o.mask, cv::Rect(530, 110, 60, 280)), 0.95);
}

}  // namespace
}  // namespace dynamap
