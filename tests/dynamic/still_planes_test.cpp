// Support planes that an earlier view saw at the same place (stillPlaneCells()) start no group of
// the dense check: a floor at a grazing angle that a pose error makes look seen through along the
// rays, against a panel slid along a wall, seen through at its leading edge.
#include <gtest/gtest.h>

#include <cmath>

#include "dynamap/core/dynamic/depth_check.hpp"
#include "dynamap/core/dynamic/support_planes.hpp"

namespace dynamap::still_planes_test {
namespace {

constexpr double kFx = 540.0, kCx = 320.0, kCy = 240.0;
const cv::Vec4d kK(kFx, kFx, kCx, kCy);
constexpr double kHeightM = 0.8, kWallM = 4.0, kPanelM = 2.0;

/// A camera 0.8 m above a floor, looking level at a wall 4 m away; with `panel_cols`, a panel
/// 2 m away over those columns (rows 60-419). Exact depth.
cv::Mat roomDepth(const cv::Range& panel_cols = cv::Range::all()) {
  cv::Mat depth(480, 640, CV_32F);
  for (int v = 0; v < depth.rows; ++v) {
    const double z_floor = v > kCy ? kHeightM * kFx / (v - kCy) : 1e9;
    for (int u = 0; u < depth.cols; ++u) {
      double z = std::min(z_floor, kWallM);
      if (panel_cols != cv::Range::all() && u >= panel_cols.start && u < panel_cols.end &&
          v >= 60 && v < 420)
        z = kPanelM;
      depth.at<float>(v, u) = static_cast<float>(z);
    }
  }
  return depth;
}

cv::Matx44d pitched(double degrees) {
  const double a = degrees * CV_PI / 180.0, c = std::cos(a), s = std::sin(a);
  return cv::Matx44d(1, 0, 0, 0, 0, c, -s, 0, 0, s, c, 0, 0, 0, 0, 1);
}

DepthView viewOf(const cv::Mat& depth, const cv::Matx44d& T_W_C) {
  DepthView v = DepthHistory::halfView(depth, 0);
  v.T_W_C = T_W_C;
  return v;
}

cv::Mat seenThroughCells(const cv::Mat& depth, const DepthView& view) {
  cv::Mat seen = cv::Mat::zeros(depth.size(), CV_8UC1);
  compareWithView(depth, cv::Mat(), cv::Rect(0, 0, depth.cols, depth.rows), cv::Matx44d::eye(), kK,
                  view, DepthCheckOptions(), &seen);
  return seen;
}

TEST(StillPlanes, AFloorThatAPoseErrorMakesLookSeenThroughStartsNoGroup) {
  const cv::Mat depth = roomDepth();
  const DepthView view = viewOf(depth, pitched(-1.0));  // the same room, its pose 1 degree off
  cv::Mat floor = cv::Mat::zeros(depth.size(), CV_8UC1);
  floor(cv::Range(static_cast<int>(kCy + kHeightM * kFx / kWallM) + 2, 480), cv::Range::all())
      .setTo(255);
  const cv::Mat seen = seenThroughCells(depth, view) & floor;
  ASSERT_GT(cv::countNonZero(seen), 2000);  // the pose error alone looks like a mover
  const SupportPlaneOptions po;
  const std::vector<Plane> planes = findSupportPlanes(depth, kK, cv::Mat(), po);
  ASSERT_FALSE(planes.empty());
  const DepthCheckOptions check;
  const cv::Mat still = stillPlaneCells(depth, cv::Matx44d::eye(), kK, view, planes, po, check);
  EXPECT_GT(cv::countNonZero(seen & still), 0.95 * cv::countNonZero(seen));
  SeenThroughOptions so;
  const cv::Mat before = seenThroughRegions(depth, cv::Matx44d::eye(), kK, view, cv::Mat(), so);
  const cv::Mat after = seenThroughRegions(depth, cv::Matx44d::eye(), kK, view, cv::Mat(), so,
                                           nullptr, [&](const cv::Mat&) { return still; });
  EXPECT_GT(cv::countNonZero(before & floor), 5000);
  EXPECT_EQ(cv::countNonZero(after), 0);
}

TEST(StillPlanes, APanelSlidAlongAWallIsStillFoundAtItsLeadingEdge) {
  const cv::Mat depth = roomDepth(cv::Range(200, 440));
  const DepthView view = viewOf(roomDepth(cv::Range(140, 380)), cv::Matx44d::eye());
  cv::Mat edge = cv::Mat::zeros(depth.size(), CV_8UC1), panel = edge.clone();
  edge(cv::Range(60, 420), cv::Range(380, 440)).setTo(255);
  panel(cv::Range(60, 420), cv::Range(200, 440)).setTo(255);
  const cv::Mat seen = seenThroughCells(depth, view) & edge;
  ASSERT_GT(cv::countNonZero(seen), 0.8 * cv::countNonZero(edge));
  const SupportPlaneOptions po;
  const std::vector<Plane> planes = findSupportPlanes(depth, kK, cv::Mat(), po);
  const cv::Mat on = planePixels(depth, kK, planes, po);
  ASSERT_GT(cv::countNonZero(on & panel), 0.95 * cv::countNonZero(panel));  // it is a plane
  const cv::Mat still =
      stillPlaneCells(depth, cv::Matx44d::eye(), kK, view, planes, po, DepthCheckOptions());
  EXPECT_LT(cv::countNonZero(still & seen), 0.02 * cv::countNonZero(seen));
  EXPECT_GT(cv::countNonZero(still & panel & ~edge), 0.9 * cv::countNonZero(panel & ~edge));
  const cv::Mat moved =
      seenThroughRegions(depth, cv::Matx44d::eye(), kK, view, cv::Mat(), SeenThroughOptions(),
                         nullptr, [&](const cv::Mat&) { return still; });
  EXPECT_GT(cv::countNonZero(moved & edge), 0.95 * cv::countNonZero(edge));
  EXPECT_GT(cv::countNonZero(moved & panel), 0.7 * cv::countNonZero(panel));
}

}  // namespace
}  // namespace dynamap::still_planes_test
