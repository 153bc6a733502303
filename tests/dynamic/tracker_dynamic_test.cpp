// Integration on real data: the first 60 frames of teddy_dyn_dev (two walkers, one standing
// person, the teddy) through Tracker + makeMotionFilter(mode both, default configuration, the
// detector asynchronous as in `dynamap run`). The trajectory is Horn-aligned to the ground truth;
// keyframe masks are scored against the ground-truth person masks.
// Measured (Release, 2 loaded cores): ATE ~0.4 cm with removal, ~16 cm without (the
// walkers take over the pose); keyframe mean IoU ~0.69, standing 0.03 %. The bounds leave room for
// the timing-dependent detector but fail if the walkers reach the pose or the masks.
#include <gtest/gtest.h>

#include <chrono>

#include "../../tools/bench_dynamic/track_harness.hpp"
#include "test_paths.hpp"

namespace dynamap {
namespace {

constexpr int kFrames = 60;

struct IntegrationRun {
  double ate_m = 0.0;
  double mean_iou = 0.0;  ///< keyframes with a moving person
  double standing = 0.0;  ///< share of standing-person pixels masked on keyframes
  double teddy = 0.0;     ///< share of teddy pixels masked on keyframes
  int keyframes = 0;
  std::size_t tracked = 0;
};

IntegrationRun runTracker(const std::string& mode) {
  DynamicConfig dc;
  dc.mode = mode;
  resolveDynamicModelPaths(dc, (test::sourceDir() / "config/default.yaml").string());
  const dynbench::DynSequence seq(test::sharedData() / "dynamic/teddy_dyn_dev");
  auto filter = makeMotionFilter(dc, PinholeCamera{}, nullptr);
  Tracker tracker(PinholeCamera{}, TrackerConfig{}, nullptr);
  tracker.setMotionFilter(filter.get());
  IntegrationRun run;
  double iou_sum = 0.0;
  int iou_n = 0;
  long st = 0, st_m = 0, td = 0, td_m = 0;
  for (int i = 0; i < kFrames; ++i) {
    const dynbench::SequenceFrame f = seq.load(static_cast<std::size_t>(i));
    const TrackingResult r = tracker.track(f.frame);
    if (!r.is_keyframe) continue;
    ++run.keyframes;
    const auto s = dynbench::scoreMask(r.keyframe->dynamic_mask, f.gt_mask, f.teddy_mask);
    if (s.moving_visible) iou_sum += s.iou, ++iou_n;
    st += s.standing_px, st_m += s.standing_masked_px;
    td += s.teddy_px, td_m += s.teddy_masked_px;
  }
  tracker.finish();
  std::vector<Eigen::Vector3d> est, ref;
  for (const auto& [stamp, T] : tracker.finalTrajectory()) {
    Eigen::Isometry3d T_gt;
    if (!seq.gtPose(stamp, &T_gt)) continue;
    est.push_back(T.translation());
    ref.push_back(T_gt.translation());
  }
  run.ate_m = dynbench::ateRmse(est, ref);
  run.mean_iou = iou_n > 0 ? iou_sum / iou_n : 0.0;
  run.standing = st > 0 ? double(st_m) / st : 0.0;
  run.teddy = td > 0 ? double(td_m) / td : 0.0;
  run.tracked = tracker.stats().tracked;
  return run;
}

TEST(TrackerWithMotionFilter, TeddyDynDevFirst60FramesWalkersStayOutOfPoseAndMap) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  const auto start = std::chrono::steady_clock::now();
  const IntegrationRun both = runTracker("both");
  const IntegrationRun off = runTracker("off");
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << "both: ATE " << both.ate_m << " m, keyframes " << both.keyframes << ", mean IoU "
            << both.mean_iou << ", standing " << both.standing << ", teddy " << both.teddy
            << " | off: ATE " << off.ate_m << " m | " << seconds << " s\n";
  EXPECT_EQ(both.tracked, static_cast<std::size_t>(kFrames));
  EXPECT_LT(both.ate_m, 0.015);            // measured 0.4-1.2 cm; clean teddy ~1 cm
  EXPECT_GT(off.ate_m, 3.0 * both.ate_m);  // the walkers corrupt the pose without removal
  EXPECT_GT(both.mean_iou, 0.5);
  // The standing person is kept once quiet frames confirm it (a person is masked until then);
  // 59 % masked over these 60 frames at this commit (issue 15 asks <= 10 %: not met), but it
  // must be kept for part of the run.
  EXPECT_LT(both.standing, 0.8);
  EXPECT_LT(both.teddy, 0.05);  // the teddy keeps its features
  EXPECT_LT(seconds, 60.0);
}

}  // namespace
}  // namespace dynamap
