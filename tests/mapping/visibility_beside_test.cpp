// Beside-a-mover votes of the visibility pass (VisibilityOptions::mask_near_px,
// mask_near_depth_m): a walker's leg shows for one keyframe, unmasked (nothing has detected the
// walker yet), and every other keyframe sees something just in front of where it was. When those
// keyframes mask what is in front (the walker, now detected), the leg goes; when nothing near it
// moves, or what moves passes far in front, it stays.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "visibility_pass.hpp"

namespace dynamap::test {
namespace {

constexpr int kKeyframes = 10;
constexpr double kPeriodS = 0.1;  // keyframes 10 Hz apart
constexpr int kLegKeyframe = 3;   // the one keyframe that sees the leg

const Box kLeg = SyntheticScene::movingBox(0);

/// Keyframes kLegKeyframe to kLegKeyframe + views - 1 see the leg, unmasked; the others see a box
/// that hides it, `share` of the way from it to the camera (0.08: ~0.2 m in front), masked when
/// `in_front_masked`.
VisibilityPass run(const VisibilityOptions& options, bool in_front_masked, double share = 0.08,
                   int views = 1, bool moved_object = false) {
  const SyntheticScene scene;
  VisibilityPass p;
  for (int k = 0; k < kKeyframes; ++k) {
    const bool leg = k >= kLegKeyframe && k < kLegKeyframe + views;
    SyntheticFrame f = scene.render(
        k, kKeyframes, leg ? kLeg : SyntheticScene::occluderFor(k, kKeyframes, kLeg, share));
    const cv::Mat mask = !leg && in_front_masked ? f.mask : cv::Mat::zeros(f.mask.size(), CV_8UC1);
    p.add(std::move(f), mask, moved_object);
  }
  p.run(options, kPeriodS);
  return p;
}

VisibilityOptions withNear(int px, int max_views = 1) {
  VisibilityOptions o;
  o.mask_near_px = px;
  o.mask_near_max_views = max_views;
  o.mask_near_object_max_views = 0;
  return o;
}

TEST(VisibilityBeside, LegShownOnceBesideMoversIsRemovedAndTheRoomStays) {
  ASSERT_GT(cv::countNonZero(SyntheticScene().render(kLegKeyframe, kKeyframes, kLeg).mask), 300);
  const VisibilityPass p = run(withNear(24), true);
  EXPECT_EQ(p.result().seen_through, 0u);        // nobody saw through it: only the votes can tell
  EXPECT_GT(p.moverRemoved(kLegKeyframe), 0.6);  // 84 %
  for (int k = 0; k < kKeyframes; ++k) {         // 0 static pixels in each
    const int px = p.pixels(k);
    EXPECT_LT(p.staticRemoved(k), 0.005 * px) << k;
  }
}

// Shows the test above can fail: without the votes the leg stays.
TEST(VisibilityBeside, WithoutTheVotesTheLegStays) {
  EXPECT_LT(run(withNear(0), true).moverRemoved(kLegKeyframe), 0.05);
}

// The same single view with nothing moving near it (what is in front is static): it stays.
TEST(VisibilityBeside, SurfaceSeenOnceWithNoMoverNearStays) {
  const VisibilityPass p = run(withNear(24), false);
  EXPECT_LT(p.moverRemoved(kLegKeyframe), 0.05);
  for (int k = 0; k < kKeyframes; ++k) EXPECT_EQ(p.staticRemoved(k), 0) << k;
}

// Someone passing halfway between the camera and a surface seen once (~1.2 m in front) is no
// evidence about that surface: it stays.
TEST(VisibilityBeside, SurfaceSeenOnceBehindAPasserByStays) {
  EXPECT_LT(run(withNear(24), true, 0.5).moverRemoved(kLegKeyframe), 0.05);
}

// An object that moved before anything detected it (a pushed chair in the first keyframes of
// a run): three keyframes in a row see it unmasked, and the later ones see the mover, now
// masked, in front of where it was. With mask_near_max_views 3 it goes; with 1 (one view only)
// it stays; the room stays either way.
TEST(VisibilityBeside, MoverSeenByThreeKeyframesBeforeItWasDetectedIsRemoved) {
  constexpr int kViews = 3;
  const VisibilityPass p = run(withNear(24, kViews), true, 0.08, kViews);
  for (int k = kLegKeyframe; k < kLegKeyframe + kViews; ++k) {
    EXPECT_GT(p.moverRemoved(k), 0.6) << k;
  }
  for (int k = 0; k < kKeyframes; ++k) EXPECT_LT(p.staticRemoved(k), 0.005 * p.pixels(k)) << k;
  EXPECT_LT(run(withNear(24, 1), true, 0.08, kViews).moverRemoved(kLegKeyframe), 0.05);
}

// Seen by more keyframes than mask_near_max_views, or with nothing masked near it, it stays.
TEST(VisibilityBeside, SurfaceSeenByMoreKeyframesOrWithNoMoverNearStays) {
  EXPECT_LT(run(withNear(24, 3), true, 0.08, 4).moverRemoved(kLegKeyframe), 0.05);
  EXPECT_LT(run(withNear(24, 3), false, 0.08, 3).moverRemoved(kLegKeyframe), 0.05);
}

// The same three views with the default options: beside a moved object that is not a person (a
// pushed chair, a mover track) the surface goes; beside a person's mask (a walker uncovers the
// background for a moment) it stays, and so it does with the object rule off or seen by a fourth.
TEST(VisibilityBeside, ByDefaultThreeViewsBesideAMovedObjectGoButNotBesideAPerson) {
  constexpr int kViews = 3;
  const VisibilityOptions defaults;
  const VisibilityPass p = run(defaults, true, 0.08, kViews, true);
  for (int k = kLegKeyframe; k < kLegKeyframe + kViews; ++k) {
    EXPECT_GT(p.moverRemoved(k), 0.6) << k;
  }
  for (int k = 0; k < kKeyframes; ++k) EXPECT_LT(p.staticRemoved(k), 0.005 * p.pixels(k)) << k;
  EXPECT_LT(run(defaults, true, 0.08, kViews, false).moverRemoved(kLegKeyframe), 0.05);
  VisibilityOptions off = defaults;
  off.mask_near_object_max_views = 0;
  EXPECT_LT(run(off, true, 0.08, kViews, true).moverRemoved(kLegKeyframe), 0.05);
  EXPECT_LT(run(defaults, true, 0.08, kViews + 1, true).moverRemoved(kLegKeyframe), 0.05);
}

}  // namespace
}  // namespace dynamap::test
