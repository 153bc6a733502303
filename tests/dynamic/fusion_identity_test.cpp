// An object's identity over time is its tracked points: a person half hidden behind something
// keeps the evidence gathered on it, and the point anchors, not one frame's flags, tell whether
// a kept person moved.
#include <functional>

#include <gtest/gtest.h>

#include "dynamap/core/dynamic/region_fusion.hpp"

namespace dynamap::fusion_identity_test {
namespace {

constexpr int kPerson = 0;
const cv::Vec4d kK(535.4, 539.2, 320.1, 247.6);

/// A still camera (the world frame) over a wall 4 m away, a grid of tracked points every 10 px.
struct Scene {
  cv::Mat depth = cv::Mat(480, 640, CV_32F, cv::Scalar(4.f));
  std::vector<cv::Point2f> points;
  std::vector<std::uint8_t> flags;
  FusionEvidence ev;

  explicit Scene(std::uint64_t first_id = 0) {
    for (int y = 5; y < 480; y += 10)
      for (int x = 5; x < 640; x += 10) points.emplace_back(float(x), float(y));
    flags.assign(points.size(), 0);
    ev.has_pose = true;
    ev.K = kK;
    for (std::size_t i = 0; i < points.size(); ++i) ev.point_ids.push_back(first_id + i);
  }
  /// Flags the points inside `r` and moves them by `shift` px.
  void disturb(const cv::Rect& r, float shift) {
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (!r.contains(cv::Point(points[i]))) continue;
      flags[i] = 1;
      points[i].x += shift;
    }
  }
  FusionResult fuse(RegionFusion& f, const std::vector<Detection>& dets) const {
    return f.fuse(FusionMode::kBoth, depth, points, flags, dets, ev);
  }
};

Detection box(const cv::Rect& r) {
  return {cv::Rect2f(r.x - 10, r.y - 10, r.width + 20, r.height + 20), kPerson, 0.9f};
}

TEST(TrackIdentity, TheTrackHoldingMostOfThePointsOfTheSameClass) {
  std::vector<ObjectTrack> tracks(3);
  tracks[0].class_id = kPerson;
  tracks[1].class_id = kPerson;
  tracks[2].class_id = 77;  // another class holding all of them
  for (std::uint64_t id : {1, 2, 3}) tracks[0].anchors.push_back({id, {}});
  for (std::uint64_t id : {4, 5, 6, 7}) tracks[1].anchors.push_back({id, {}});
  for (std::uint64_t id = 1; id <= 7; ++id) tracks[2].anchors.push_back({id, {}});
  EXPECT_EQ(trackSharingPoints({2, 3, 5, 6, 7, 9}, tracks, kPerson, 3), 1);
  EXPECT_EQ(trackSharingPoints({1, 2, 3, 9}, tracks, kPerson, 3), 0);
  EXPECT_EQ(trackSharingPoints({1, 2, 9}, tracks, kPerson, 3), -1);  // too few
  EXPECT_EQ(trackSharingPoints({1, 2, 3}, tracks, 77, 3), 2);
}

/// Runs `frames` frames of one RegionFusion; `frame(s, i)` sets up frame i's scene and returns
/// its detections. Returns whether the first object is masked in each frame from `from` on.
std::vector<bool> maskedFrom(int frames, int from,
                             const std::function<std::vector<Detection>(Scene&, int)>& frame,
                             const DynamicConfig& c = DynamicConfig()) {
  RegionFusion fusion(c, ClassTable(c));
  std::vector<bool> masked;
  for (int i = 0; i < frames; ++i) {
    Scene s;
    const std::vector<Detection> dets = frame(s, i);
    const bool m = s.fuse(fusion, dets).objects.at(0).moving;
    if (i == from - 1) {
      EXPECT_FALSE(m) << "confirmed still before frame " << from;
    }
    if (i >= from) masked.push_back(m);
  }
  return masked;
}

/// Frames 0-9 a person stands 2 m away, fully seen; from frame 10 a crate 1 m away hides all
/// but their head (a box of a quarter of the IoU association needs). Returns whether they are
/// masked in frames 10-14.
std::vector<bool> hiddenPersonMasked(bool with_ids) {
  const cv::Rect person(280, 100, 80, 280), head(280, 100, 80, 60);
  const cv::Rect crate(200, 170, 240, 300);
  return maskedFrom(15, 10, [&](Scene& s, int i) {
    if (!with_ids) s.ev.point_ids.clear();
    s.depth(person).setTo(2.f);
    if (i >= 10) s.depth(crate).setTo(1.f);
    return std::vector<Detection>{box(i < 10 ? person : head)};
  });
}

TEST(TrackIdentity, AHalfHiddenStandingPersonKeepsTheEvidenceOnItsPoints) {
  for (const bool m : hiddenPersonMasked(true)) EXPECT_FALSE(m);
  // Associated by box overlap only, the head is a new person: masked until confirmed again.
  const std::vector<bool> by_box = hiddenPersonMasked(false);
  EXPECT_TRUE(by_box.front());
}

/// A person confirmed still for 10 frames; in frames 10 .. 10 + off - 1 all their points are
/// flagged and seen `jump_px` off (the flags of those frames); then they are back where they
/// were. Masked per frame from 10 on (18 frames in all).
std::vector<bool> maskedAfterFlaggedFrames(float jump_px, int off,
                                           const DynamicConfig& c = DynamicConfig()) {
  const cv::Rect person(280, 100, 80, 280);
  return maskedFrom(
      18, 10,
      [&](Scene& s, int i) {
        s.depth(person).setTo(2.f);
        if (i >= 10 && i < 10 + off) s.disturb(person, jump_px);
        return std::vector<Detection>{box(person)};
      },
      c);
}

TEST(TrackIdentity, OneFlaggedFrameTheAnchorsDoNotConfirmMasksButDoesNotRestartTheCount) {
  // 6 px: beyond the anchors' still limit (at 2 m static_anchor_m's 1.5 cm, 4.0 px; more than
  // static_anchor_px 3), within twice it.
  const std::vector<bool> jitter = maskedAfterFlaggedFrames(6.f, 1);
  EXPECT_TRUE(jitter[0]);   // removing takes one frame
  EXPECT_FALSE(jitter[1]);  // back in place: kept at once, the count went on
}

// Anchors off by more than twice the still limit (10 px) in one frame only: masked in it, kept
// at once after (the count goes on); in two frames in a row: the count starts again
// (static_confirm_frames = 5: masked in the two and at least the 4 frames after).
TEST(TrackIdentity, AConfirmedPersonsAnchorsFarOffInOneFrameOnlyDoNotRestartTheCount) {
  const std::vector<bool> once = maskedAfterFlaggedFrames(10.f, 1);
  EXPECT_TRUE(once[0]);
  for (std::size_t i = 1; i < once.size(); ++i) EXPECT_FALSE(once[i]) << i;
  const std::vector<bool> twice = maskedAfterFlaggedFrames(10.f, 2);
  for (std::size_t i = 0; i < 6; ++i) EXPECT_TRUE(twice[i]) << i;
  // static_anchor_move_frames = 1: the first such frame restarts the count.
  DynamicConfig first;
  first.static_anchor_move_frames = 1;
  const std::vector<bool> at_once = maskedAfterFlaggedFrames(10.f, 1, first);
  for (std::size_t i = 0; i < 5; ++i) EXPECT_TRUE(at_once[i]) << i;
}

}  // namespace
}  // namespace dynamap::fusion_identity_test
