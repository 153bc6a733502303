// Short real-data check on teddy_dyn_dev (frames 20-40: two walkers and the standing person
// in view), without the tracker: LK matches between consecutive frames, the motion filter,
// masks scored against the ground-truth person masks. The detector runs as it ships (its own
// thread in lockstep: frame i uses frame i-1's detections) at its default input. Bounds are set
// below what the default configuration reaches on these frames (IoU 0.72, standing person 0.56,
// teddy 0.0; naive detector-only masks standing 0.84) so that the test fails on a real
// regression, not on noise.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "../../tools/bench_dynamic/dynamic_harness.hpp"
#include "dynamap/core/dynamic/dynamic_motion_filter.hpp"
#include "test_paths.hpp"

namespace dynamap {
namespace {

struct RunScore {
  double mean_iou = 0.0, standing = 0.0, teddy = 0.0;
};

RunScore run(const std::string& mode, int first, int count) {
  DynamicConfig c;
  c.mode = mode;
  resolveDynamicModelPaths(c, (test::sourceDir() / "config/default.yaml").string());
  DynamicMotionFilter filter(c, PinholeCamera{}, nullptr);
  const dynbench::DynSequence seq(test::sharedData() / "dynamic/teddy_dyn_dev");
  dynbench::SequenceFrame prev = seq.load(first);
  double iou_sum = 0.0;
  int iou_n = 0;
  long st = 0, st_m = 0, td = 0, td_m = 0;
  for (int i = first + 1; i <= first + count; ++i) {
    dynbench::SequenceFrame cur = seq.load(i);
    filter.beginFrame(cur.frame);
    const FeatureMatches m = dynbench::trackLk(prev.gray, cur.gray);
    const MotionFilterOutput out = filter.filter({&cur.frame, &prev.gray, &cur.gray, &m});
    EXPECT_EQ(out.match_is_dynamic.size(), m.cur_px.size());
    const auto s = dynbench::scoreMask(out.dynamic_mask, cur.gt_mask, cur.teddy_mask);
    if (s.moving_visible) iou_sum += s.iou, ++iou_n;
    st += s.standing_px, st_m += s.standing_masked_px, td += s.teddy_px, td_m += s.teddy_masked_px;
    prev = std::move(cur);
  }
  return {iou_n ? iou_sum / iou_n : 0.0, st ? double(st_m) / st : 0.0,
          td ? double(td_m) / td : 0.0};
}

TEST(TeddyDynDev, FusionMasksWalkersAndKeepsTheStandingPersonAndTheTeddy) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  const RunScore both = run("both", 19, 20);
  EXPECT_GE(both.mean_iou, 0.6);
  EXPECT_LE(both.teddy, 0.05);
  // The naive baseline masks every detected person, the standing one included.
  const RunScore naive = run("detector", 19, 20);
  EXPECT_GE(naive.standing, 0.5);
  EXPECT_GT(both.mean_iou, naive.mean_iou);
  // A person is kept only after quiet frames measured against a background-only camera motion
  // (evidence over time), so the standing person is masked while that evidence gathers, and
  // again for a few frames after each residual spike (frames 26 and 35): at least a quarter of
  // what the naive baseline masks of it must be kept. (Issue 15 asks <= 10 %: not met. With the
  // detector run synchronously on each frame's own image it is 0.56 at input 256, 0.31 at 320.)
  EXPECT_LT(both.standing, 0.75 * naive.standing);
}

}  // namespace
}  // namespace dynamap

namespace dynamap {
namespace {

// The filter destroyed while its detector thread is still on a frame (a run that stops right
// after handing a frame over): the destructor joins that thread before the filter's own members
// go, so the frame's timing lands in live recorders only. Under AddressSanitizer
// (scripts/sanitize.sh) the old member order failed here: heap-use-after-free in
// TimingRecorder::add on the detector thread (the detection takes ~15-25 ms at 256 x 256; 10 ms
// after the hand-over it is running on a 2-core machine). In other builds this only checks that
// the destructor neither hangs nor records a frame twice.
TEST(DynamicMotionFilter, DestroyedWhileItsDetectorRuns) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  DynamicConfig c;
  resolveDynamicModelPaths(c, (test::sourceDir() / "config/default.yaml").string());
  const dynbench::DynSequence seq(test::sharedData() / "dynamic/teddy_dyn_dev");
  const dynbench::SequenceFrame frame = seq.load(20);
  TimingRecorder timing;
  {
    DynamicMotionFilter filter(c, PinholeCamera{}, &timing);
    filter.beginFrame(frame.frame);  // handed to the detector thread
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_LE(timing.stats("detector").count, 1u);
}

}  // namespace
}  // namespace dynamap

namespace dynamap {
namespace {

// dynamic.detector_every_frames: in a lockstep run only every Nth frame goes to the detector
// (the first always); the frames between still get the newest detections, moved and grown.
TEST(DynamicMotionFilter, DetectsEveryNthFrameAndMasksTheOthersFromTheNewest) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  DynamicConfig c;
  c.detector_every_frames = 3;
  resolveDynamicModelPaths(c, (test::sourceDir() / "config/default.yaml").string());
  const dynbench::DynSequence seq(test::sharedData() / "dynamic/teddy_dyn_dev");
  TimingRecorder timing;
  int masked_frames = 0;
  {
    DynamicMotionFilter filter(c, PinholeCamera{}, &timing);
    dynbench::SequenceFrame prev = seq.load(20);
    for (int i = 21; i <= 29; ++i) {  // 9 frames: numbers 0-8, detected 0, 3, 6
      dynbench::SequenceFrame cur = seq.load(i);
      filter.beginFrame(cur.frame);
      const FeatureMatches m = dynbench::trackLk(prev.gray, cur.gray);
      const MotionFilterOutput out = filter.filter({&cur.frame, &prev.gray, &cur.gray, &m});
      if (!out.dynamic_mask.empty() && cv::countNonZero(out.dynamic_mask) > 0) ++masked_frames;
      prev = std::move(cur);
    }
  }
  EXPECT_EQ(timing.stats("detector").count, 3u);
  // Walkers are in view on every one of these frames: each frame but the first (which has no
  // motion evidence yet) has a mask, the undetected ones included.
  EXPECT_GE(masked_frames, 8);
}

}  // namespace
}  // namespace dynamap
