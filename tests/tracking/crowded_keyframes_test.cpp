// Keyframes while movers fill the view: none for lack of tracks alone (kf_max_masked_share),
// unless the tracks left are too few to hold the pose (kf_crowded_min_tracks); the landmarks a
// mover uncovers are found again (refind_below_tracks).
#include <algorithm>

#include <gtest/gtest.h>

#include "dynamap/core/tracker.hpp"
#include "synthetic_scene.hpp"
#include "tracking_test_utils.hpp"

namespace dynamap::crowded_keyframes_test {
namespace {

constexpr double kFramePeriodS = 1.0 / 30.0;
constexpr int kFrames = 40;
constexpr int kSlow = 300;  // ~4 mm a frame: the motion limits make a keyframe every 20 frames

/// Masks a band of the image (as moving) in frames [first, last] only: `first_share` of its
/// width at `first`, growing by `growth` a frame up to `last_share`, from the left border moving
/// right by `sweep_px` a frame (a walker crossing the view).
class CrowdedSpanFilter : public MotionFilter {
 public:
  struct Span {
    int first = 10, last = 25;
    double first_share = 0.6, growth = 0.0, last_share = 0.6;
    int sweep_px = 0;
  };
  CrowdedSpanFilter(int width, int height, Span span)
      : width_(width), height_(height), span_(span) {}
  void beginFrame(const RgbdFrame&) override {}
  MotionFilterOutput filter(const MotionFilterInput& input) override {
    const int frame = frame_++;
    MotionFilterOutput out;
    if (frame < span_.first || frame > span_.last) {
      out.match_is_dynamic.assign(input.matches->cur_px.size(), 0);
      return out;
    }
    const double share =
        std::min(span_.last_share, span_.first_share + span_.growth * (frame - span_.first));
    const int from = std::min(width_, span_.sweep_px * (frame - span_.first));
    const int to = std::min(width_, from + static_cast<int>(width_ * share));
    out.dynamic_mask = cv::Mat::zeros(height_, width_, CV_8UC1);
    out.dynamic_mask.colRange(from, to).setTo(255);
    for (const auto& p : input.matches->cur_px) {
      out.match_is_dynamic.push_back(p.x >= from && p.x < to);
    }
    return out;
  }

 private:
  int width_, height_;
  Span span_;
  int frame_ = 0;
};

struct CrowdedRun {
  int keyframes_in_span = 0, tracked = 0;
  int fewest_inliers_after_span = 1 << 30;  ///< frames 26-39, after the movers left
  double worst_m = 0.0;
};

/// 40 frames of the room on a slow path; in frames 10-25 movers fill the left of the image.
CrowdedRun trackThroughACrowd(const TrackerConfig& config, CrowdedSpanFilter::Span span) {
  const PinholeCamera camera = cameraPreset("freiburg3");
  test::SyntheticScene scene(camera, 23);
  scene.addDefaultRoom();
  CrowdedSpanFilter filter(camera.width, camera.height, span);
  Tracker tracker(camera, config, nullptr);
  tracker.setMotionFilter(&filter);
  CrowdedRun run;
  for (int i = 0; i < kFrames; ++i) {
    const auto r = scene.render(test::smoothPath(i, kSlow), i * kFramePeriodS);
    RgbdFrame frame;
    frame.index = static_cast<std::size_t>(i);
    frame.timestamp_s = i * kFramePeriodS;
    frame.bgr = r.bgr;
    frame.depth_m = r.depth_m;
    const TrackingResult res = tracker.track(frame);
    run.tracked += res.status == FrameStatus::kTracked;
    run.keyframes_in_span += res.is_keyframe && i >= 10 && i <= 25;
    if (i > 25)
      run.fewest_inliers_after_span = std::min(run.fewest_inliers_after_span, res.inliers);
  }
  tracker.finish();
  const auto traj = tracker.finalTrajectory();
  for (std::size_t i = 0; i < traj.size(); ++i) {
    const Eigen::Isometry3d truth =
        test::smoothPath(0, kSlow).inverse() * test::smoothPath(static_cast<int>(i), kSlow);
    run.worst_m =
        std::max(run.worst_m, (traj[i].second.translation() - truth.translation()).norm());
  }
  return run;
}

TrackerConfig withMaskedShareLimit(double kf_max_masked_share, int kf_crowded_min_tracks,
                                   int refind_below_tracks = 0) {
  TrackerConfig config;
  config.kf_max_masked_share = kf_max_masked_share;
  config.kf_crowded_min_tracks = kf_crowded_min_tracks;
  config.refind_below_tracks = refind_below_tracks;
  return config;
}

TEST(SyntheticTracking, FramesTheMoversFillMakeKeyframesOnlyForMotionNotForLackOfTracks) {
  const CrowdedRun always = trackThroughACrowd(withMaskedShareLimit(1.0, 0), {});
  const CrowdedRun crowded = trackThroughACrowd(withMaskedShareLimit(0.35, 0), {});
  // Masking 60 % of the view drops the tracks below the keyframe limits at once: without the
  // share limit a keyframe follows; with it, only the motion and time limits make one.
  EXPECT_GT(always.keyframes_in_span, crowded.keyframes_in_span);
  EXPECT_EQ(crowded.tracked, kFrames);
  EXPECT_LT(crowded.worst_m, 0.015);
}

TEST(SyntheticTracking, AFrameTheMoversFillMakesAKeyframeBeforeItsTracksRunOut) {
  // Movers spreading from 50 % to 94 % of the view leave too few tracks to hold the pose
  // through the crowd, unless keyframes seed the rest of the view on the way.
  const CrowdedSpanFilter::Span spreading{10, 25, 0.5, 0.04, 0.94};
  const CrowdedRun starved = trackThroughACrowd(withMaskedShareLimit(0.35, 0), spreading);
  const CrowdedRun fed = trackThroughACrowd(withMaskedShareLimit(0.35, 45), spreading);
  EXPECT_LT(starved.tracked, kFrames);
  EXPECT_GT(fed.keyframes_in_span, starved.keyframes_in_span);
  EXPECT_EQ(fed.tracked, kFrames);
  EXPECT_LT(fed.worst_m, 0.015);
}

TEST(SyntheticTracking, LandmarksAWalkerUncoversAreFoundAgainWhileTracksRunShort) {
  // A band of 40 % of the view crosses it from the left (16 px a frame): every track it passes
  // over goes, and the landmarks behind it come back into view untracked.
  const CrowdedSpanFilter::Span crossing{10, 25, 0.4, 0.0, 0.4, 16};
  const CrowdedRun plain = trackThroughACrowd(withMaskedShareLimit(0.35, 45, 0), crossing);
  const CrowdedRun refound = trackThroughACrowd(withMaskedShareLimit(0.35, 45, 1000), crossing);
  EXPECT_EQ(plain.tracked, kFrames);
  EXPECT_EQ(refound.tracked, kFrames);
  // Without the search, the view the walker left is tracked again only through the landmarks
  // of a new keyframe; with it, through the old ones at once.
  EXPECT_GT(refound.fewest_inliers_after_span, plain.fewest_inliers_after_span);
  EXPECT_LE(refound.keyframes_in_span, plain.keyframes_in_span);
  EXPECT_LT(refound.worst_m, 0.015);
}

}  // namespace
}  // namespace dynamap::crowded_keyframes_test
