#include <gtest/gtest.h>

#include "dynamap/core/dynamic/region_fusion.hpp"
#include "mask_share.hpp"

namespace dynamap {
namespace {

// No detection. A wall at 3 m; an undetected mover at 1.5 m that was 60 px to the left in the
// earlier view; and a patch of wall whose tracked points are falsely flagged dynamic (as LK
// tracks dragged beside a walker are). The camera stands still.
struct ClusterScene {
  cv::Mat depth = cv::Mat(480, 640, CV_32F, cv::Scalar(3.f));
  cv::Rect mover{300, 150, 100, 150}, mover_before{240, 150, 100, 150},
      false_flags{100, 200, 60, 60};
  std::vector<cv::Point2f> points;
  std::vector<std::uint8_t> dynamic;
  DepthView view;
  FusionEvidence evidence;

  ClusterScene() {
    depth(mover).setTo(1.5f);
    view.depth_m = cv::Mat(480, 640, CV_32F, cv::Scalar(3.f));
    view.depth_m(mover_before).setTo(1.5f);
    for (int y = 5; y < 480; y += 10) {
      for (int x = 5; x < 640; x += 10) {
        points.emplace_back(static_cast<float>(x), static_cast<float>(y));
        dynamic.push_back(mover.contains({x, y}) || false_flags.contains({x, y}) ? 1 : 0);
      }
    }
    evidence.has_pose = true;
    evidence.K = cv::Vec4d(540.0, 540.0, 320.0, 240.0);
    evidence.view = &view;
  }
};

using test::maskedShare;

FusionResult fuseScene(const ClusterScene& s, const DynamicConfig& c) {
  RegionFusion fusion(c, ClassTable(c));
  return fusion.fuse(FusionMode::kBoth, s.depth, s.points, s.dynamic, {}, s.evidence);
}

TEST(ClusterInPlace, AClusterTheEarlierViewSawInPlaceIsNotMasked) {
  ClusterScene s;
  DynamicConfig c;
  const FusionResult r = fuseScene(s, c);
  EXPECT_EQ(r.clusters, 1);
  EXPECT_GT(maskedShare(r.mask, s.mover), 0.95);
  EXPECT_LT(maskedShare(r.mask, s.false_flags), 0.01);
}

TEST(ClusterInPlace, WithoutAnEarlierViewOrTheCheckBothClustersAreMasked) {
  ClusterScene s;
  DynamicConfig c;
  s.evidence.view = nullptr;
  const FusionResult a = fuseScene(s, c);
  EXPECT_EQ(a.clusters, 2);
  EXPECT_GT(maskedShare(a.mask, s.false_flags), 0.95);

  s.evidence.view = &s.view;
  c.cluster_max_consistent = 0.0;  // off
  const FusionResult b = fuseScene(s, c);
  EXPECT_EQ(b.clusters, 2);
  EXPECT_GT(maskedShare(b.mask, s.mover), 0.95);
}

// The wall 6 m away, beyond the range where the sensor's depth says a surface moved
// (cluster_max_depth_m, 5 m), and no earlier view: the flagged patch on it is not masked, the mover
// at 1.5 m is. With no range both are.
TEST(ClusterInPlace, FlagsOnAWallBeyondTheTrustedDepthMaskNothing) {
  ClusterScene s;
  s.depth.setTo(6.f);
  s.depth(s.mover).setTo(1.5f);
  s.evidence.view = nullptr;
  DynamicConfig c;
  const FusionResult r = fuseScene(s, c);
  EXPECT_EQ(r.clusters, 1);
  EXPECT_GT(maskedShare(r.mask, s.mover), 0.95);
  EXPECT_LT(maskedShare(r.mask, s.false_flags), 0.01);

  c.cluster_max_depth_m = 0.0;  // any range
  const FusionResult b = fuseScene(s, c);
  EXPECT_EQ(b.clusters, 2);
  EXPECT_GT(maskedShare(b.mask, s.false_flags), 0.95);
}

}  // namespace
}  // namespace dynamap
