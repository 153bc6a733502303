// Tracker::markBadFrame(timestamp_s): a frame that could not be read is counted and its
// timestamp kept (badFrameTimestamps()), and it takes no place in the trajectory.
// Named SyntheticTracking.* so that ctest labels it "threaded" (the tracker runs the BA thread).
#include <gtest/gtest.h>

#include <algorithm>

#include "dynamap/core/tracker.hpp"
#include "synthetic_scene.hpp"
#include "tracking_test_utils.hpp"

namespace dynamap {
namespace {

TEST(SyntheticTracking, BadFramesKeepTheirTimestampsAndGetNoPose) {
  const PinholeCamera camera = cameraPreset("freiburg3");
  test::SyntheticScene scene(camera, 12);
  scene.addDefaultRoom();
  Tracker tracker(camera, TrackerConfig{}, nullptr);
  constexpr double kPeriodS = 1.0 / 30.0;
  const std::vector<int> bad = {3, 5, 6};  // frames that "could not be read"
  std::vector<double> good_timestamps;
  for (int i = 0; i < 9; ++i) {
    const double t_s = 100.0 + i * kPeriodS;
    if (std::find(bad.begin(), bad.end(), i) != bad.end()) {
      tracker.markBadFrame(t_s);
      continue;
    }
    const auto r = scene.render(test::smoothPath(i, 60), t_s);
    RgbdFrame frame;
    frame.index = static_cast<std::size_t>(i);
    frame.timestamp_s = t_s;
    frame.bgr = r.bgr;
    frame.depth_m = r.depth_m;
    EXPECT_EQ(tracker.track(frame).status, FrameStatus::kTracked) << "frame " << i;
    good_timestamps.push_back(t_s);
  }
  tracker.finish();

  const std::vector<double> bad_timestamps = tracker.badFrameTimestamps();
  ASSERT_EQ(bad_timestamps.size(), bad.size());
  for (std::size_t k = 0; k < bad.size(); ++k) {
    EXPECT_DOUBLE_EQ(bad_timestamps[k], 100.0 + bad[k] * kPeriodS);
  }
  const auto trajectory = tracker.finalTrajectory();
  ASSERT_EQ(trajectory.size(), good_timestamps.size());
  for (std::size_t k = 0; k < trajectory.size(); ++k) {
    EXPECT_DOUBLE_EQ(trajectory[k].first, good_timestamps[k]);
  }
  EXPECT_EQ(tracker.frameStatuses().size(), good_timestamps.size());
  const TrackerStats s = tracker.stats();
  EXPECT_EQ(s.frames, 9u);
  EXPECT_EQ(s.bad_frames, bad.size());
  EXPECT_EQ(s.tracked, good_timestamps.size());
}

}  // namespace
}  // namespace dynamap
