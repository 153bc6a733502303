// The first pose in a loaded map (core/src/tracking/tracker_load.cpp): a pose with too few
// inliers to start tracking from (reloc_min_inliers) is the frame's pose when the frame before
// gave the same (reportAgreeingPose()); tracking, and with it any keyframe, waits for a pose with
// enough. Where run 2 starts in a crowd that hides the mapped background, such poses come back
// frame after frame for 20 frames (teddy's map, teddy_dyn_crowd_dev played backward).
#include <gtest/gtest.h>

#include "dynamap/core/tracker.hpp"
#include "synthetic_scene.hpp"
#include "tracking_test_utils.hpp"

namespace dynamap {
namespace {

constexpr int kFrames = 60;

struct FirstFrames {
  std::vector<FrameStatus> statuses;
  std::vector<double> errors_m;  ///< of the frames with a pose
  std::size_t trajectory_size = 0;
  std::size_t keyframes = 0;
};

/// Frames [0, n) of `scene` along the saved run's path, in `saved`, with `config`.
FirstFrames runInSavedMap(const test::SyntheticScene& scene, const MapContents& saved,
                          const TrackerConfig& config, int n) {
  Tracker tracker(scene.camera(), config, nullptr);
  tracker.loadMap(saved);
  FirstFrames out;
  for (int i = 0; i < n; ++i) {
    const Eigen::Isometry3d truth = test::smoothPath(i, kFrames);
    const test::RenderedFrame r = scene.render(truth, 0.0);
    RgbdFrame f;
    f.index = static_cast<std::size_t>(i);
    f.timestamp_s = 100.0 + i / 30.0;
    f.bgr = r.bgr;
    f.depth_m = r.depth_m;
    const TrackingResult res = tracker.track(f);
    out.statuses.push_back(res.status);
    if (res.status != FrameStatus::kLost)
      out.errors_m.push_back((res.T_W_C.translation() - truth.translation()).norm());
  }
  out.trajectory_size = tracker.finalTrajectory().size();
  out.keyframes = tracker.keyframes().size() - saved.keyframes.size();
  return out;
}

TEST(LoadedMapFirstPose, PosesWithTooFewInliersThatAgreeAreReportedAndTrackingWaits) {
  test::SyntheticScene room(cameraPreset("freiburg3"), 21);
  room.addDefaultRoom();
  const MapContents saved = test::savedMapAlongSmoothPath(room, kFrames);
  TrackerConfig never_enough;
  never_enough.reloc_min_inliers = 100000;  // no pose is enough to start tracking from
  const FirstFrames run = runInSavedMap(room, saved, never_enough, 8);
  EXPECT_EQ(run.statuses.front(), FrameStatus::kLost);  // no frame before it to agree with
  for (std::size_t i = 1; i < run.statuses.size(); ++i)
    EXPECT_EQ(run.statuses[i], FrameStatus::kRelocalized) << "frame " << i;
  ASSERT_EQ(run.errors_m.size(), 7u);
  for (const double e : run.errors_m) EXPECT_LT(e, 0.01);  // in the saved map's frame
  EXPECT_EQ(run.trajectory_size, 7u);                      // frame 0 has no pose
  EXPECT_EQ(run.keyframes, 0u);                            // tracking never started

  // With the default limit the first frame already has enough: tracking starts at once.
  const FirstFrames normal = runInSavedMap(room, saved, TrackerConfig{}, 8);
  EXPECT_EQ(normal.statuses.front(), FrameStatus::kRelocalized);
  for (std::size_t i = 1; i < normal.statuses.size(); ++i)
    EXPECT_EQ(normal.statuses[i], FrameStatus::kTracked) << "frame " << i;
}

}  // namespace
}  // namespace dynamap
