#include <utility>

#include <gtest/gtest.h>

#include <iostream>

#include "dynamap/core/tracker.hpp"
#include "synthetic_scene.hpp"
#include "tracking_test_utils.hpp"

namespace dynamap {
namespace {

constexpr int kFrames = 60;
constexpr double kFramePeriodS = 1.0 / 30.0;

RgbdFrame makeFrame(const test::RenderedFrame& r, int i) {
  RgbdFrame f;
  f.index = static_cast<std::size_t>(i);
  f.timestamp_s = i * kFramePeriodS;
  f.bgr = r.bgr;
  f.depth_m = r.depth_m;
  return f;
}

/// Translation error of frame i against the truth re-expressed in frame 0's camera frame.
double translationError(const Eigen::Isometry3d& est, int i) {
  const Eigen::Isometry3d truth =
      test::smoothPath(0, kFrames).inverse() * test::smoothPath(i, kFrames);
  return (est.translation() - truth.translation()).norm();
}

TEST(SyntheticTracking, SmoothSixDofSequenceHasSubCentimetreAte) {
  const PinholeCamera camera = cameraPreset("freiburg3");
  test::SyntheticScene scene(camera, 11);
  scene.addDefaultRoom();
  TimingRecorder timings;
  Tracker tracker(camera, TrackerConfig{}, &timings);
  int keyframes = 0;
  for (int i = 0; i < kFrames; ++i) {
    const auto r = scene.render(test::smoothPath(i, kFrames), i * kFramePeriodS);
    const TrackingResult res = tracker.track(makeFrame(r, i));
    EXPECT_EQ(res.status, FrameStatus::kTracked) << "frame " << i;
    EXPECT_EQ(res.is_keyframe, static_cast<bool>(res.keyframe));
    keyframes += res.is_keyframe ? 1 : 0;
    if (i == 0) {
      EXPECT_TRUE(res.is_keyframe);
      EXPECT_TRUE(res.T_W_C.isApprox(Eigen::Isometry3d::Identity()));
    }
  }
  tracker.finish();
  const auto traj = tracker.finalTrajectory();
  ASSERT_EQ(traj.size(), static_cast<std::size_t>(kFrames));
  double sum2 = 0.0;
  for (int i = 0; i < kFrames; ++i) {
    const double e = translationError(traj[static_cast<std::size_t>(i)].second, i);
    sum2 += e * e;
  }
  const double ate = std::sqrt(sum2 / kFrames);
  std::cout << "[synthetic] ATE RMSE " << ate * 100 << " cm, keyframes " << keyframes
            << ", median tracking " << timings.stats("tracking").median_ms << " ms\n";
  EXPECT_LT(ate, 0.01);  // world frame = frame 0, no alignment needed
  EXPECT_GT(keyframes, 1);
  EXPECT_EQ(tracker.stats().tracked, static_cast<std::size_t>(kFrames));
  EXPECT_EQ(tracker.keyframes().size(), static_cast<std::size_t>(keyframes));
  EXPECT_GT(timings.stats("lk").count, 0u);
  EXPECT_GT(timings.stats("orb").count, 0u);
  EXPECT_LT(timings.stats("orb").count, static_cast<std::size_t>(kFrames));  // not every frame
}

constexpr int kBlackFirst = 25, kBlackLast = 28, kBlankRunFrames = 45;

/// The room's 45 frames, frames kBlackFirst..kBlackLast with black colour images (depth kept):
/// the live statuses and keyframe flags of those frames, then the tracker's outputs.
struct BlankColourRun {
  std::vector<FrameStatus> blank_status;
  std::vector<bool> blank_keyframe;
  std::vector<FrameStatus> statuses;
  std::vector<std::pair<double, Eigen::Isometry3d>> trajectory;
  TrackerStats stats;
};

/// `bad_frame_after` >= 0: a bad frame is marked after that frame. `black_last`: the last black
/// frame.
BlankColourRun trackBlankColour(const TrackerConfig& config, int bad_frame_after,
                                int black_last = kBlackLast) {
  const PinholeCamera camera = cameraPreset("freiburg3");
  test::SyntheticScene scene(camera, 12);
  scene.addDefaultRoom();
  Tracker tracker(camera, config, nullptr);
  BlankColourRun run;
  for (int i = 0; i < kBlankRunFrames; ++i) {
    auto r = scene.render(test::smoothPath(i, kFrames), i * kFramePeriodS);
    const bool blank = i >= kBlackFirst && i <= black_last;
    if (blank) r.bgr.setTo(cv::Scalar::all(0));
    const TrackingResult res = tracker.track(makeFrame(r, i));
    if (blank) {
      run.blank_status.push_back(res.status);
      run.blank_keyframe.push_back(res.is_keyframe);
    }
    if (i == bad_frame_after) tracker.markBadFrame(i * kFramePeriodS + 0.01);
  }
  tracker.finish();
  run.statuses = tracker.frameStatuses();
  run.trajectory = tracker.finalTrajectory();
  run.stats = tracker.stats();
  return run;
}

// Black colour images with depth and the depth fallback off: tracking is lost and must
// relocalize afterwards.
TEST(SyntheticTracking, BlankFramesAreLostThenRelocalized) {
  TrackerConfig config;
  config.depth_fallback = false;
  const BlankColourRun run = trackBlankColour(config, 30);
  for (const FrameStatus status : run.blank_status) EXPECT_EQ(status, FrameStatus::kLost);
  ASSERT_EQ(run.statuses.size(), 45u);
  EXPECT_EQ(run.statuses[kBlackLast + 1], FrameStatus::kRelocalized);
  for (int i = kBlackLast + 2; i < kBlankRunFrames; ++i) {
    EXPECT_EQ(run.statuses[static_cast<std::size_t>(i)], FrameStatus::kTracked) << "frame " << i;
  }
  for (int i = kBlackLast + 1; i < kBlankRunFrames; ++i) {
    EXPECT_LT(translationError(run.trajectory[static_cast<std::size_t>(i)].second, i), 0.02) << i;
  }
  const TrackerStats& s = run.stats;
  EXPECT_EQ(s.frames, 46u);
  EXPECT_EQ(s.bad_frames, 1u);
  EXPECT_EQ(s.lost, static_cast<std::size_t>(kBlackLast - kBlackFirst + 1));
  EXPECT_EQ(s.relocalized, 1u);
  EXPECT_EQ(s.tracked + s.relocalized + s.lost + s.bad_frames, s.frames);
}

// The same frames with the depth fallback (the default), as where people fill the view: the
// depth of the static pixels poses them, none is lost and none makes a keyframe; the features
// come back by relocalization. Tolerance: 1 cm, a third of the 4 frames' motion.
TEST(SyntheticTracking, BlankFramesWithDepthArePosedByTheDepthAlone) {
  const BlankColourRun run = trackBlankColour(TrackerConfig{}, -1);
  for (const FrameStatus status : run.blank_status) EXPECT_EQ(status, FrameStatus::kPosedByDepth);
  for (const bool keyframe : run.blank_keyframe) EXPECT_FALSE(keyframe);
  ASSERT_EQ(run.trajectory.size(), 45u);
  const double moved = (test::smoothPath(kBlackFirst - 1, kFrames).translation() -
                        test::smoothPath(kBlackLast, kFrames).translation())
                           .norm();
  ASSERT_GT(moved, 0.03);
  for (int i = kBlackFirst; i < kBlankRunFrames; ++i) {
    EXPECT_LT(translationError(run.trajectory[static_cast<std::size_t>(i)].second, i), 0.01) << i;
  }
  EXPECT_EQ(run.stats.lost, 0u);
  EXPECT_EQ(run.stats.posed_by_depth, static_cast<std::size_t>(kBlackLast - kBlackFirst + 1));
  EXPECT_LE(run.stats.relocalized, 1u);
}

// Black for longer than tracking.restart_after_lost_frames (5): five frames are posed by depth,
// the map restarts, and the first frame with colour again starts it; the frames after it track
// its new features (a stale "posed by depth" once dropped them, and they were posed by depth).
TEST(SyntheticTracking, AMapRestartedAfterDepthPosedFramesKeepsItsNewTracks) {
  const int black_last = kBlackFirst + 11;
  const BlankColourRun run = trackBlankColour(TrackerConfig{}, -1, black_last);
  EXPECT_EQ(run.stats.posed_by_depth, 5u);
  ASSERT_EQ(run.statuses.size(), static_cast<std::size_t>(kBlankRunFrames));
  for (int i = black_last + 1; i < kBlankRunFrames; ++i) {
    EXPECT_EQ(run.statuses[static_cast<std::size_t>(i)], FrameStatus::kTracked) << "frame " << i;
  }
}

TEST(SyntheticTracking, BlankFramesWithoutDepthAreLostAndTrackingResumes) {
  const PinholeCamera camera = cameraPreset("freiburg3");
  test::SyntheticScene scene(camera, 16);
  scene.addDefaultRoom();
  Tracker tracker(camera, TrackerConfig{}, nullptr);
  constexpr int kBlankFirst = 25, kBlankLast = 27;
  for (int i = 0; i < 40; ++i) {
    auto r = scene.render(test::smoothPath(i, kFrames), i * kFramePeriodS);
    const bool blank = i >= kBlankFirst && i <= kBlankLast;
    if (blank) {  // both streams drop out: the frames are lost but the tracker keeps its state
      r.bgr.setTo(cv::Scalar::all(0));
      r.depth_m.setTo(0.f);
    }
    const TrackingResult res = tracker.track(makeFrame(r, i));
    EXPECT_EQ(res.status, blank ? FrameStatus::kLost : FrameStatus::kTracked) << "frame " << i;
    if (!blank) {
      EXPECT_LT(translationError(res.T_W_C, i), 0.02) << "frame " << i;
    }
  }
  const TrackerStats s = tracker.stats();
  EXPECT_EQ(s.lost, static_cast<std::size_t>(kBlankLast - kBlankFirst + 1));
  EXPECT_EQ(s.relocalized, 0u);
}

TEST(SyntheticTracking, FrameWithoutDepthIsPosedButMakesNoKeyframe) {
  const PinholeCamera camera = cameraPreset("freiburg3");
  test::SyntheticScene scene(camera, 14);
  scene.addDefaultRoom();
  TrackerConfig config;
  config.kf_max_interval_s = 0.01;  // every frame asks for a keyframe
  Tracker tracker(camera, config, nullptr);
  constexpr int kNoDepth = 12;
  for (int i = 0; i < 20; ++i) {
    auto r = scene.render(test::smoothPath(i, kFrames), i * kFramePeriodS);
    if (i == kNoDepth) r.depth_m.setTo(0.f);
    const TrackingResult res = tracker.track(makeFrame(r, i));
    EXPECT_EQ(res.status, FrameStatus::kTracked) << "frame " << i;
    // No landmark can start without depth: the frame is posed by reprojection alone, and the
    // next frame (with depth) becomes the keyframe instead.
    EXPECT_EQ(res.is_keyframe, i != kNoDepth) << "frame " << i;
    EXPECT_LT(translationError(res.T_W_C, i), 0.01) << "frame " << i;
  }
}

TEST(SyntheticTracking, FrameWithoutDepthChangesNoOtherPose) {
  const PinholeCamera camera = cameraPreset("freiburg3");
  test::SyntheticScene scene(camera, 15);
  scene.addDefaultRoom();
  // One tracker sees 20 frames; the other the same frames plus a depthless frame halfway between
  // frames 11 and 12 (as a colour frame with no depth frame near it). Offline tracking is
  // deterministic, so every shared frame must get the very same pose.
  Tracker plain(camera, TrackerConfig{}, nullptr);
  Tracker with_gap(camera, TrackerConfig{}, nullptr);
  constexpr int kGapAfter = 11;
  for (int i = 0; i < 20; ++i) {
    const auto r = scene.render(test::smoothPath(i, kFrames), i * kFramePeriodS);
    const TrackingResult a = plain.track(makeFrame(r, i));
    const TrackingResult b = with_gap.track(makeFrame(r, i));
    EXPECT_TRUE(a.T_W_C.isApprox(b.T_W_C, 1e-12)) << "frame " << i;
    if (i != kGapAfter) continue;
    auto gap = scene.render(test::smoothPath(2 * i + 1, 2 * kFrames), (i + 0.5) * kFramePeriodS);
    gap.depth_m.setTo(0.f);
    RgbdFrame f = makeFrame(gap, i);
    f.timestamp_s = (i + 0.5) * kFramePeriodS;
    const TrackingResult g = with_gap.track(f);
    EXPECT_EQ(g.status, FrameStatus::kTracked);
    EXPECT_FALSE(g.is_keyframe);
    const Eigen::Isometry3d truth =
        test::smoothPath(0, kFrames).inverse() * test::smoothPath(2 * i + 1, 2 * kFrames);
    EXPECT_LT((g.T_W_C.translation() - truth.translation()).norm(), 0.01);
  }
  plain.finish();
  with_gap.finish();
  EXPECT_EQ(with_gap.finalTrajectory().size(), plain.finalTrajectory().size() + 1);
}

/// Flags every match and masks every pixel of the moving box (from the renderer's mask).
class OracleMotionFilter : public MotionFilter {
 public:
  void beginFrame(const RgbdFrame& frame) override {
    ++begun;
    mask = masks.at(frame.index);
  }
  MotionFilterOutput filter(const MotionFilterInput& input) override {
    ++filtered;
    MotionFilterOutput out;
    out.dynamic_mask = mask;
    for (const auto& p : input.matches->cur_px) {
      out.match_is_dynamic.push_back(mask.at<std::uint8_t>(cvRound(p.y), cvRound(p.x)) == 255);
    }
    return out;
  }
  std::vector<cv::Mat> masks;
  cv::Mat mask;
  int begun = 0, filtered = 0;
};

TEST(SyntheticTracking, MovingBoxIsMaskedOutAndPoseStaysAccurate) {
  const PinholeCamera camera = cameraPreset("freiburg3");
  test::SyntheticScene scene(camera, 13);
  scene.addDefaultRoom();
  scene.addMovingBox({-0.2, 0.0, 1.6}, {0.3, 0.3, 0.3}, {0.6, 0.0, 0.0});
  OracleMotionFilter oracle;
  std::vector<test::RenderedFrame> frames;
  for (int i = 0; i < 40; ++i) {
    frames.push_back(scene.render(test::smoothPath(i, kFrames), i * kFramePeriodS));
    oracle.masks.push_back(frames.back().mask);
  }
  Tracker tracker(camera, TrackerConfig{}, nullptr);
  tracker.setMotionFilter(&oracle);
  int dynamic = 0;
  for (int i = 0; i < 40; ++i) {
    const TrackingResult res = tracker.track(makeFrame(frames[static_cast<std::size_t>(i)], i));
    dynamic += res.dynamic_matches;
    EXPECT_NE(res.status, FrameStatus::kLost);
    if (res.is_keyframe) {
      ASSERT_FALSE(res.keyframe->dynamic_mask.empty());
      EXPECT_EQ(
          cv::countNonZero(res.keyframe->dynamic_mask != oracle.masks[static_cast<std::size_t>(i)]),
          0);
    }
  }
  tracker.finish();
  EXPECT_EQ(oracle.begun, 40);
  EXPECT_EQ(oracle.filtered, 40);
  // No landmark is created on the masked box, but the box slides over tracked background:
  // those tracks land inside its mask and must be dropped, not used for the pose.
  EXPECT_GT(dynamic, 0);
  const auto traj = tracker.finalTrajectory();
  for (int i = 0; i < 40; ++i) {
    EXPECT_LT(translationError(traj[static_cast<std::size_t>(i)].second, i), 0.015) << i;
  }
}

}  // namespace
}  // namespace dynamap

namespace dynamap {
namespace {

/// Frames after a long blank in a room the map has never seen (relocalization cannot work):
/// how many of the last 10 are tracked.
int trackedAfterLongLoss(int restart_after_lost_frames) {
  const PinholeCamera camera = cameraPreset("freiburg3");
  test::SyntheticScene first(camera, 12), other(camera, 99);
  first.addDefaultRoom();
  other.addDefaultRoom();
  TrackerConfig config;
  config.restart_after_lost_frames = restart_after_lost_frames;
  Tracker tracker(camera, config, nullptr);
  constexpr int kBlankFirst = 15, kBlankLast = 34, kEnd = 50;
  int tracked = 0;
  for (int i = 0; i < kEnd; ++i) {
    auto r =
        (i < kBlankFirst ? first : other).render(test::smoothPath(i, kFrames), i * kFramePeriodS);
    if (i >= kBlankFirst && i <= kBlankLast) r.bgr.setTo(cv::Scalar::all(0));
    const TrackingResult res = tracker.track(makeFrame(r, i));
    tracked += i >= kEnd - 10 && res.status == FrameStatus::kTracked;
  }
  tracker.finish();
  return tracked;
}

TEST(SyntheticTracking, ALongLossRestartsTheMapWhereTheCameraWasLastSeen) {
  // 20 blank frames, then a room the map has never seen: without a restart the tracker stays
  // lost for good; with one (after 15 lost frames) it tracks again.
  EXPECT_EQ(trackedAfterLongLoss(0), 0);
  EXPECT_EQ(trackedAfterLongLoss(15), 10);
}

/// Masks the same still region in every frame; as an unconfirmed object (a teddy taken for a
/// person, not yet shown to stand still) or as one with evidence of motion.
class StillRegionFilter : public MotionFilter {
 public:
  StillRegionFilter(cv::Mat region, bool unconfirmed)
      : region_(std::move(region)), unconfirmed_(unconfirmed) {}
  void beginFrame(const RgbdFrame&) override {}
  MotionFilterOutput filter(const MotionFilterInput& input) override {
    MotionFilterOutput out;
    out.dynamic_mask = region_;
    if (unconfirmed_) out.unconfirmed_mask = region_;
    for (const auto& p : input.matches->cur_px) {
      const bool in = region_.at<std::uint8_t>(cvRound(p.y), cvRound(p.x)) == 255;
      out.match_is_dynamic.push_back(in);
      out.match_held.push_back(in && unconfirmed_);
    }
    return out;
  }

 private:
  cv::Mat region_;
  bool unconfirmed_;
};

/// 30 frames of the room with all but an 8 px border masked; returns the frames tracked and
/// the largest position error.
std::pair<int, double> trackWithMostlyMaskedView(bool unconfirmed) {
  const PinholeCamera camera = cameraPreset("freiburg3");
  test::SyntheticScene scene(camera, 21);
  scene.addDefaultRoom();
  cv::Mat region = cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
  region(cv::Rect(8, 8, camera.width - 16, camera.height - 16)).setTo(255);
  StillRegionFilter filter(region, unconfirmed);
  Tracker tracker(camera, TrackerConfig{}, nullptr);
  tracker.setMotionFilter(&filter);
  int tracked = 0;
  for (int i = 0; i < 30; ++i) {
    const auto r = scene.render(test::smoothPath(i, kFrames), i * kFramePeriodS);
    tracked += tracker.track(makeFrame(r, i)).status == FrameStatus::kTracked;
  }
  tracker.finish();
  double worst = 0.0;
  const auto traj = tracker.finalTrajectory();
  for (std::size_t i = 0; i < traj.size(); ++i) {
    worst = std::max(worst, translationError(traj[i].second, static_cast<int>(i)));
  }
  return {tracked, worst};
}

TEST(SyntheticTracking, AMapStartsOnUnconfirmedObjectsWhenTheRestIsTooLittleToTrack) {
  // Too few features outside the masked region: a map started there is lost at once.
  EXPECT_LT(trackWithMostlyMaskedView(false).first, 15);
  // The region is only unconfirmed (nothing says it moves): the first keyframe takes its
  // features too, and every frame is tracked.
  const auto [tracked, worst_m] = trackWithMostlyMaskedView(true);
  EXPECT_EQ(tracked, 30);
  EXPECT_LT(worst_m, 0.015);
}

}  // namespace
}  // namespace dynamap
