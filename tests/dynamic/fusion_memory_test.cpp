// A person confirmed still, hidden from the detector longer than his track lasts (walkers in
// front of him), is remembered: found again with his own points where they were, he is kept at
// once; moved on, he is masked until he proves still again.
#include <gtest/gtest.h>

#include "fusion_point_grid.hpp"

namespace dynamap::fusion_memory_test {
namespace {

const cv::Vec4d kK(535.4, 539.2, 320.1, 247.6);
const Detection& kPersonBox = test::kSidewaysPersonBox;  // 2 m away, before a wall 5 m away

/// 20 frames seen still, `hidden` frames undetected, then detected again `shift` px to the
/// side: whether he is masked in the first frame he is seen again.
bool maskedWhenSeenAgain(const DynamicConfig& c, int hidden, float shift) {
  FusionEvidence ev;
  ev.has_pose = true;
  ev.K = kK;
  RegionFusion fusion(c, ClassTable(c));
  for (int i = 0; i < 20; ++i) {
    const test::SidewaysFrame f = test::sidewaysFrame(0.f, false, ev);
    const FusionResult r =
        fusion.fuse(FusionMode::kBoth, f.depth, f.points, f.flags, {kPersonBox}, ev);
    if (i == 19) {
      EXPECT_FALSE(r.objects.at(0).moving) << "kept before he is hidden";
    }
  }
  for (int i = 0; i < hidden; ++i) {
    const test::SidewaysFrame f = test::sidewaysFrame(0.f, false, ev);
    fusion.fuse(FusionMode::kBoth, f.depth, f.points, f.flags, {}, ev);
  }
  const test::SidewaysFrame f = test::sidewaysFrame(shift, false, ev);
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
