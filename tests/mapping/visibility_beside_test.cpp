// Beside-a-mover votes of the visibility pass (VisibilityOptions::mask_near_px): a walker's leg
// shows for one keyframe, unmasked (nothing has detected the walker yet), and every other
// keyframe sees something in front of where it was. When those keyframes mask what is in front
// (the walker, now detected), the leg goes; when nothing near it moves, it stays.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "dynamap/mapping/visibility.hpp"
#include "synthetic_scene.hpp"

namespace dynamap::test {
namespace {

constexpr int kKeyframes = 10;
constexpr double kPeriodS = 0.1;  // keyframes 10 Hz apart
constexpr int kLegKeyframe = 3;   // the one keyframe that sees the leg

const Box kLeg = SyntheticScene::movingBox(0);

struct Pass {
  std::vector<SyntheticFrame> frames;
  std::vector<cv::Mat> depths;  // static depth: masked pixels 0, edited by the pass
  VisibilityResult result;
};

/// Keyframe kLegKeyframe sees the leg, unmasked; the others see a box in front of it, masked
/// when `in_front_masked`.
Pass run(const VisibilityOptions& options, bool in_front_masked) {
  const SyntheticScene scene;
  Pass p;
  std::vector<cv::Mat> masks;
  for (int k = 0; k < kKeyframes; ++k) {
    const bool leg = k == kLegKeyframe;
    p.frames.push_back(
        scene.render(k, kKeyframes, leg ? kLeg : SyntheticScene::occluderFor(k, kKeyframes, kLeg)));
    const SyntheticFrame& f = p.frames.back();
    masks.push_back(!leg && in_front_masked ? f.mask : cv::Mat::zeros(f.mask.size(), CV_8UC1));
    p.depths.push_back(f.depth_m.clone());
    p.depths.back().setTo(0.0f, masks.back());
  }
  std::vector<VisibilityView> views;
  for (int k = 0; k < kKeyframes; ++k)
    views.push_back(makeVisibilityView(p.frames[k].depth_m, masks[k], options));
  std::vector<VisibilityKeyframe> kfs;
  for (int k = 0; k < kKeyframes; ++k) {
    VisibilityKeyframe kf{&p.depths[k], 1.0, p.frames[k].T_W_C, &views[k]};
    kf.timestamp_s = kPeriodS * k;
    kfs.push_back(kf);
  }
  p.result = removeSeenThrough(SyntheticScene::camera(), kfs, options);
  return p;
}

/// Share of the leg's pixels the pass removed.
double legRemoved(const Pass& p) {
  const SyntheticFrame& f = p.frames[kLegKeyframe];
  const cv::Mat leg = (f.mask == 255) & (f.depth_m > 0);
  const cv::Mat kept = leg & (p.depths[kLegKeyframe] > 0);
  return 1.0 - static_cast<double>(cv::countNonZero(kept)) / std::max(1, cv::countNonZero(leg));
}

/// Pixels of the static room (neither leg nor the boxes in front of it) removed in keyframe k.
int staticRemoved(const Pass& p, int k) {
  const cv::Mat removed = (p.depths[k] == 0) & (p.frames[k].depth_m > 0);
  return cv::countNonZero(removed & (p.frames[k].mask == 0));
}

VisibilityOptions withNear(int px) {
  VisibilityOptions o;
  o.mask_near_px = px;
  return o;
}

TEST(VisibilityBeside, LegShownOnceBesideMoversIsRemovedAndTheRoomStays) {
  ASSERT_GT(cv::countNonZero(SyntheticScene().render(kLegKeyframe, kKeyframes, kLeg).mask), 300);
  const Pass p = run(withNear(24), true);
  EXPECT_EQ(p.result.seen_through, 0u);  // nobody saw through it: only the votes can tell
  EXPECT_GT(legRemoved(p), 0.6);
  for (int k = 0; k < kKeyframes; ++k) {
    const int px = cv::countNonZero(p.frames[k].depth_m > 0);
    EXPECT_LT(staticRemoved(p, k), 0.005 * px) << k;
  }
}

// Shows the test above can fail: without the votes the leg stays.
TEST(VisibilityBeside, WithoutTheVotesTheLegStays) {
  EXPECT_LT(legRemoved(run(withNear(0), true)), 0.05);
}

// The same single view with nothing moving near it (what is in front is static): it stays.
TEST(VisibilityBeside, SurfaceSeenOnceWithNoMoverNearStays) {
  const Pass p = run(withNear(24), false);
  EXPECT_LT(legRemoved(p), 0.05);
  for (int k = 0; k < kKeyframes; ++k) EXPECT_EQ(staticRemoved(p, k), 0) << k;
}

}  // namespace
}  // namespace dynamap::test
