#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "dynamap/core/dynamic/dynamic_motion_filter.hpp"
#include "dynamap/core/dynamic/region_fusion.hpp"
#include "mask_share.hpp"

namespace dynamap {
namespace {

// A synthetic depth scene: wall at 4 m, floor-free; a standing person A at 2 m, a walking
// person B at 2.5 m, and an undetected mover C at 1.5 m. Tracked points on a 10 px grid.
struct Scene {
  cv::Mat depth = cv::Mat(480, 640, CV_32F, cv::Scalar(4.f));
  cv::Rect person_a{100, 150, 80, 250}, person_b{400, 150, 80, 250}, mover_c{250, 40, 60, 60};
  std::vector<cv::Point2f> points;
  std::vector<std::uint8_t> dynamic;
  std::vector<Detection> detections;

  Scene() {
    depth(person_a).setTo(2.f);
    depth(person_b).setTo(2.5f);
    depth(mover_c).setTo(1.5f);
    for (int y = 5; y < 480; y += 10) {
      for (int x = 5; x < 640; x += 10) {
        points.emplace_back(static_cast<float>(x), static_cast<float>(y));
        const bool moving = person_b.contains({x, y}) || mover_c.contains({x, y});
        dynamic.push_back(moving ? 1 : 0);
      }
    }
    // Boxes a bit larger than the people: the wall inside them must not be masked.
    detections.push_back({cv::Rect2f(85, 130, 110, 290), 0, 0.9f});
    detections.push_back({cv::Rect2f(385, 130, 110, 290), 0, 0.8f});
  }
};

using test::maskedShare;

double iouWith(const cv::Mat& mask, const cv::Rect& r) {
  cv::Mat truth = cv::Mat::zeros(mask.size(), CV_8UC1);
  truth(r).setTo(255);
  return cv::countNonZero(mask & truth) / static_cast<double>(cv::countNonZero(mask | truth));
}

TEST(RegionFusion, ObjectPixelsCutTheBoxByDepth) {
  Scene s;
  double mode = 0.0;
  const cv::Mat px = objectPixels(s.depth, cv::Rect(s.detections[0].box), 0.4, &mode);
  EXPECT_NEAR(mode, 2.0, 0.05);
  EXPECT_GT(iouWith(px, s.person_a), 0.95);
}

TEST(RegionFusion, MasksTheMovingPersonAndKeepsTheStandingOne) {
  Scene s;
  DynamicConfig c;
  RegionFusion fusion(c, ClassTable(c));
  // A person is kept only after static_confirm_frames quiet frames (fusion_time_test.cpp).
  FusionResult r;
  for (int i = 0; i <= c.static_confirm_frames; ++i)
    r = fusion.fuse(FusionMode::kBoth, s.depth, s.points, s.dynamic, s.detections);
  ASSERT_EQ(r.objects.size(), 2u);
  EXPECT_FALSE(r.objects[0].moving);
  EXPECT_TRUE(r.objects[1].moving);
  EXPECT_LT(maskedShare(r.mask, s.person_a), 0.01);
  EXPECT_GT(maskedShare(r.mask, s.person_b), 0.99);
  // Wall inside B's box, beyond the dilation, stays.
  EXPECT_EQ(cv::countNonZero(r.mask(cv::Rect(386, 135, 4, 4))), 0);
  // The undetected mover C is found from its dynamic points and grown on depth.
  EXPECT_EQ(r.clusters, 1);
  EXPECT_GT(maskedShare(r.mask, s.mover_c), 0.95);
}

TEST(RegionFusion, HysteresisNeedsEvidenceToSwitchAndHoldsThroughAQuietFrame) {
  Scene s;
  DynamicConfig c;
  RegionFusion fusion(c, ClassTable(c));
  // Frame 1: B moving. Frame 2: B's points look static once (e.g. it paused): still moving.
  EXPECT_TRUE(
      fusion.fuse(FusionMode::kBoth, s.depth, s.points, s.dynamic, s.detections).objects[1].moving);
  std::vector<std::uint8_t> quiet(s.dynamic.size(), 0);
  EXPECT_TRUE(
      fusion.fuse(FusionMode::kBoth, s.depth, s.points, quiet, s.detections).objects[1].moving);
  // Enough static frames (static_confirm_frames): B is released.
  bool moving = true;
  for (int i = 0; i < c.static_confirm_frames; ++i)
    moving =
        fusion.fuse(FusionMode::kBoth, s.depth, s.points, quiet, s.detections).objects[1].moving;
  EXPECT_FALSE(moving);
  // A single frame with a few dynamic points on A (noise) does not turn A moving.
  std::vector<std::uint8_t> noisy(s.dynamic.size(), 0);
  int flagged = 0;
  for (std::size_t i = 0; i < s.points.size() && flagged < 3; ++i) {
    if (s.person_a.contains(cv::Point(s.points[i]))) noisy[i] = 1, ++flagged;
  }
  EXPECT_FALSE(
      fusion.fuse(FusionMode::kBoth, s.depth, s.points, noisy, s.detections).objects[0].moving);
}

TEST(RegionFusion, DetectorModeMasksEveryPersonAndGeometryModeNoBox) {
  Scene s;
  DynamicConfig c;
  RegionFusion det(c, ClassTable(c));
  const FusionResult rd =
      det.fuse(FusionMode::kDetector, s.depth, s.points, s.dynamic, s.detections);
  EXPECT_GT(maskedShare(rd.mask, s.person_a), 0.99);
  EXPECT_GT(maskedShare(rd.mask, s.person_b), 0.99);
  EXPECT_LT(maskedShare(rd.mask, s.mover_c), 0.01);  // no motion check, no clusters

  RegionFusion geo(c, ClassTable(c));
  const FusionResult rg =
      geo.fuse(FusionMode::kGeometry, s.depth, s.points, s.dynamic, s.detections);
  EXPECT_TRUE(rg.objects.empty());
  EXPECT_LT(maskedShare(rg.mask, s.person_a), 0.01);
  EXPECT_GT(maskedShare(rg.mask, s.person_b), 0.95);
  EXPECT_GT(maskedShare(rg.mask, s.mover_c), 0.95);
}

TEST(MotionFilterFactory, ModesAndThreadedDetectorPlumbing) {
  DynamicConfig c;
  c.mode = "off";
  EXPECT_EQ(makeMotionFilter(c, PinholeCamera{}, nullptr), nullptr);
  c.mode = "sideways";
  EXPECT_THROW(makeMotionFilter(c, PinholeCamera{}, nullptr), std::invalid_argument);
  c.mode = "geometry";
  TimingRecorder timing;
  auto filter = makeMotionFilter(c, PinholeCamera{}, &timing);
  ASSERT_NE(filter, nullptr);
  // No matches at all: a value, not an exception; nothing dynamic.
  Scene s;
  RgbdFrame frame;
  frame.bgr = cv::Mat(480, 640, CV_8UC3, cv::Scalar::all(90));
  frame.depth_m = s.depth;
  const cv::Mat gray(480, 640, CV_8UC1, cv::Scalar(90));
  const FeatureMatches none;
  filter->beginFrame(frame);
  const MotionFilterOutput out = filter->filter({&frame, &gray, &gray, &none});
  EXPECT_TRUE(out.match_is_dynamic.empty());
  EXPECT_TRUE(out.dynamic_mask.empty());
  EXPECT_EQ(timing.stats("epipolar").count, 1u);
  EXPECT_EQ(timing.stats("fusion").count, 1u);
}

}  // namespace
}  // namespace dynamap
