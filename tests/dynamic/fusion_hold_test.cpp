// A chair the detector knows, pushed straight away from the camera: its tracked points slide
// along their rays, so no reprojection or epipolar check flags them, but their world anchors
// drift off frame after frame (dynamic.hold_moved_objects). Once it stands still long enough it
// is kept again.
#include <gtest/gtest.h>

#include "dynamap/core/dynamic/region_fusion.hpp"
#include "fusion_point_grid.hpp"

namespace dynamap::fusion_hold_test {
namespace {

const cv::Rect kChair(260, 200, 120, 200);
constexpr int kMovingFrames = 40;  ///< 1.5 cm a frame away from the camera (0.45 m/s at 30 Hz)
constexpr int kStillFrames = 40;

/// Per frame, whether the chair was masked (decided moving): the camera is still, the chair's
/// points keep their ids and pixels and are never flagged. With `person`, a person's box
/// covers the chair's.
std::vector<bool> maskedFrames(const DynamicConfig& c, bool person = false) {
  const std::vector<cv::Point2f> points = test::pointGrid();
  const std::vector<std::uint8_t> quiet(points.size(), 0);
  const FusionEvidence ev = test::stillCameraEvidence(points.size(), true);
  RegionFusion fusion(c, ClassTable(c));
  const int chair_class = ClassTable::classIndex("chair");
  std::vector<Detection> detections{{cv::Rect2f(kChair), chair_class, 0.8f}};
  if (person) detections.push_back({cv::Rect2f(kChair) + cv::Size2f(20.f, 40.f), 0, 0.9f});
  std::vector<bool> masked;
  for (int i = 0; i < kMovingFrames + kStillFrames; ++i) {
    const double z = 1.5 + 0.015 * std::min(i, kMovingFrames);
    cv::Mat depth(480, 640, CV_32F, cv::Scalar(5.f));
    depth(kChair).setTo(static_cast<float>(z));
    const FusionResult r = fusion.fuse(FusionMode::kBoth, depth, points, quiet, detections, ev);
    bool moving = false;
    for (const auto& o : r.objects) moving = moving || (o.detection.class_id == chair_class && o.moving);
    masked.push_back(moving);
  }
  return masked;
}

double share(const std::vector<bool>& v, int from, int to) {
  int n = 0;
  for (int i = from; i < to; ++i) n += v[static_cast<std::size_t>(i)];
  return n / static_cast<double>(to - from);
}

TEST(FusionHold, AChairPushedAwayFromTheCameraIsMaskedUntilItStandsStill) {
  DynamicConfig held;
  held.hold_moved_objects = true;
  const std::vector<bool> with = maskedFrames(held);
  DynamicConfig c;
  c.hold_moved_objects = false;
  const std::vector<bool> without = maskedFrames(c);
  // Its anchors are off by twice the 3 cm depth limit after 5 frames; from then on it is held
  // (a new run of anchors starts at each such frame).
  EXPECT_GT(share(with, 10, kMovingFrames), 0.9);
  EXPECT_LT(share(without, 10, kMovingFrames), 0.1);
  // Still for static_confirm_frames (and for the anchors' run to settle): kept.
  const int settled = kMovingFrames + 2 * held.static_confirm_frames + 2;
  EXPECT_EQ(share(with, settled, kMovingFrames + kStillFrames), 0.0);
}

TEST(FusionHold, AChairUnderAPersonsBoxIsNotHeld) {
  // A walker passing in front of a chair moves its points: that is no evidence of the chair's.
  DynamicConfig held;
  held.hold_moved_objects = true;
  const std::vector<bool> under = maskedFrames(held, true);
  EXPECT_LT(share(under, 10, kMovingFrames), 0.1);
}

}  // namespace
}  // namespace dynamap::fusion_hold_test
