// A person confirmed still, hidden from the detector longer than his track lasts (walkers in
// front of him), is remembered: found again with his own points where they were, he is kept at
// once; moved on, he is masked until he proves still again.
#include <gtest/gtest.h>

#include "dynamap/core/dynamic/region_fusion.hpp"

namespace dynamap::fusion_memory_test {
namespace {

const cv::Vec4d kK(535.4, 539.2, 320.1, 247.6);
const cv::Rect kPerson(280, 120, 90, 260);  // 2 m away, in front of a wall 5 m away
const Detection kPersonBox{cv::Rect2f(260, 110, 130, 280), 0, 0.9f};

struct Frame {
  std::vector<cv::Point2f> points;
  std::vector<std::uint8_t> flags;
  cv::Mat depth;
};

/// A point every 10 px (ids in `ev`), those on the person shifted `shift` px sideways.
Frame frameWithPerson(float shift, FusionEvidence& ev) {
  Frame f;
  ev.point_ids.clear();
  for (int y = 5; y < 480; y += 10) {
    for (int x = 5; x < 640; x += 10) {
      const bool on = kPerson.contains({x, y});
      f.points.emplace_back(static_cast<float>(x) + (on ? shift : 0.f), static_cast<float>(y));
      f.flags.push_back(0);
      ev.point_ids.push_back(f.points.size() - 1);
    }
  }
  f.depth = cv::Mat(480, 640, CV_32F, cv::Scalar(5.f));
  f.depth(kPerson + cv::Point(cvRound(shift), 0)).setTo(2.f);
  return f;
}

/// 20 frames seen still, `hidden` frames undetected, then detected again `shift` px to the
/// side: whether he is masked in the first frame he is seen again.
bool maskedWhenSeenAgain(const DynamicConfig& c, int hidden, float shift) {
  FusionEvidence ev;
  ev.has_pose = true;
  ev.K = kK;
  RegionFusion fusion(c, ClassTable(c));
  for (int i = 0; i < 20; ++i) {
    const Frame f = frameWithPerson(0.f, ev);
    const FusionResult r =
        fusion.fuse(FusionMode::kBoth, f.depth, f.points, f.flags, {kPersonBox}, ev);
    if (i == 19) {
      EXPECT_FALSE(r.objects.at(0).moving) << "kept before he is hidden";
    }
  }
  for (int i = 0; i < hidden; ++i) {
    const Frame f = frameWithPerson(0.f, ev);
    fusion.fuse(FusionMode::kBoth, f.depth, f.points, f.flags, {}, ev);
  }
  const Frame f = frameWithPerson(shift, ev);
  Detection seen = kPersonBox;
  seen.box.x += shift;
  const FusionResult r = fusion.fuse(FusionMode::kBoth, f.depth, f.points, f.flags, {seen}, ev);
  return r.objects.at(0).moving;
}

TEST(FusionMemory, AStillPersonHiddenLongerThanHisTrackIsKeptWhenSeenAgain) {
  DynamicConfig c;
  const int hidden = c.track_max_missed_frames + 5;
  EXPECT_FALSE(maskedWhenSeenAgain(c, hidden, 0.f));
  c.remember_still_frames = 0;  // forgotten: held until he proves still again
  EXPECT_TRUE(maskedWhenSeenAgain(c, hidden, 0.f));
}

TEST(FusionMemory, APersonWhoMovedWhileHiddenIsMasked) {
  DynamicConfig c;
  // 20 px at 2 m: 7.5 cm, beyond twice the still limit.
  EXPECT_TRUE(maskedWhenSeenAgain(c, c.track_max_missed_frames + 5, 20.f));
}

TEST(FusionMemory, AStillPersonIsForgottenAfterRememberStillFrames) {
  DynamicConfig c;
  c.remember_still_frames = 10;
  EXPECT_FALSE(maskedWhenSeenAgain(c, c.track_max_missed_frames + 5, 0.f));
  EXPECT_TRUE(maskedWhenSeenAgain(c, c.track_max_missed_frames + 12, 0.f));
}

}  // namespace
}  // namespace dynamap::fusion_memory_test
