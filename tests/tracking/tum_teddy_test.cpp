#include <gtest/gtest.h>

#include <time.h>

#include <algorithm>
#include <iostream>
#include <vector>

#include "dynamap/core/tracker.hpp"
#include "test_paths.hpp"
#include "trajectory_eval.hpp"
#include "tum_dataset.hpp"

namespace dynamap {
namespace {

constexpr std::size_t kRgbEntries = 200;  // the first 200 colour images (193 associate)
constexpr double kMaxDtS = 0.02;

std::filesystem::path teddyDir() {
  return test::sharedData() / "tum" / "rgbd_dataset_freiburg3_teddy";
}

/// The associated colour/depth frames among the first kRgbEntries colour images (the dataset
/// reader's association, depth within kMaxDtS). Loaded once per test binary.
const std::vector<RgbdFrame>& teddyFrames() {
  static const std::vector<RgbdFrame> frames = [] {
    DatasetOptions options;
    options.max_time_diff_s = kMaxDtS;
    options.keep_unassociated_rgb = true;  // one entry per colour image, depth_path "" if none
    const TumSequence seq = TumSequence::open(teddyDir().string(), options);
    std::vector<RgbdFrame> out;
    for (std::size_t k = 0; k < std::min(seq.size(), kRgbEntries); ++k) {
      if (seq.entries()[k].depth_path.empty()) continue;
      FrameLoad load = seq.load(k);
      if (!load.ok) continue;
      load.frame.index = out.size();
      out.push_back(std::move(load.frame));
    }
    return out;
  }();
  return frames;
}

double threadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

struct TeddyRun {
  std::vector<double> cpu_ms;  ///< CPU time of each track() call on the calling thread
  double ate_m = 1e9;
  std::size_t gt_matched = 0;
  std::vector<FrameStatus> statuses;
  TrackerStats stats;
};

/// Tracks every frame (colour of frames in [blank_first, blank_first + blank_count) blacked out)
/// and computes the ATE of the final trajectory (evaluate_ate.py: association within kMaxDtS,
/// Horn alignment without scale).
TeddyRun runTeddy(TimingRecorder* timings, int blank_first, int blank_count,
                  const TrackerConfig& config = {}) {
  const auto& frames = teddyFrames();
  const std::vector<TimedPose> gt = readTrajectory((teddyDir() / "groundtruth.txt").string());
  Tracker tracker(cameraPreset("freiburg3"), config, timings);
  TeddyRun run;
  for (const auto& f : frames) {
    const double cpu_start = threadCpuMs();
    const int i = static_cast<int>(f.index);
    if (i >= blank_first && i < blank_first + blank_count) {
      RgbdFrame blank = f;
      blank.bgr = cv::Mat::zeros(f.bgr.size(), f.bgr.type());
      tracker.track(blank);
    } else {
      tracker.track(f);
    }
    run.cpu_ms.push_back(threadCpuMs() - cpu_start);
  }
  tracker.finish();
  run.statuses = tracker.frameStatuses();
  run.stats = tracker.stats();
  std::vector<TimedPose> est;
  for (const auto& [t, T_W_C] : tracker.finalTrajectory()) est.push_back({t, T_W_C});
  TrajectoryEvalOptions options;
  options.max_time_diff_s = kMaxDtS;
  const AteResult ate = computeAte(gt, est, options);
  run.gt_matched = ate.pairs;
  run.ate_m = ate.error_m.rmse;
  return run;
}

// Measured in Release on the 2-core machine (BA on its own thread, load average ~10 from other
// builds): ATE RMSE 0.8-1.1 cm over repeated runs (BA timing makes runs slightly
// non-deterministic), all 193 frames posed, median "tracking" 13-15 ms wall clock, ~5 ms CPU
// of the calling thread. The target is 2 cm; the 3 cm assertion keeps a margin.
TEST(TumTeddy, First200FramesAllPosedWithLowAte) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  ASSERT_GE(teddyFrames().size(), 190u);
  const std::size_t n = teddyFrames().size();
  TimingRecorder timings;
  const TeddyRun run = runTeddy(&timings, -1, 0);
  ASSERT_EQ(run.statuses.size(), n);
  const std::size_t posed = static_cast<std::size_t>(
      std::count_if(run.statuses.begin(), run.statuses.end(),
                    [](FrameStatus s) { return s != FrameStatus::kLost; }));
  std::cout << "[teddy200] ATE RMSE " << run.ate_m * 100 << " cm over " << run.gt_matched
            << " gt-matched frames; posed share " << static_cast<double>(posed) / n << " (tracked "
            << run.stats.tracked << ", relocalized " << run.stats.relocalized << ", lost "
            << run.stats.lost << "), keyframes " << run.stats.keyframes << "\n";
  for (const auto& [stage, st] : timings.allStats()) {
    std::cout << "[teddy200] " << stage << ": n=" << st.count << " median " << st.median_ms
              << " ms, p95 " << st.p95_ms << " ms, max " << st.max_ms << " ms\n";
  }
  std::cout << "[teddy200] tracking CPU time of the calling thread: median "
            << percentile(run.cpu_ms, 50) << " ms, p95 " << percentile(run.cpu_ms, 95)
            << " ms (wall-clock stages above include waiting for a core on a loaded machine)\n";
  EXPECT_EQ(posed, n);
  EXPECT_GT(run.gt_matched, n * 9 / 10);
  EXPECT_LE(run.ate_m, 0.03);
}

constexpr int kBlankFirst = 100, kBlankCount = 4;

/// Teddy with black colour images (depth kept) at frames kBlankFirst.. (kBlankCount of them),
/// each of which must have `status`.
TeddyRun runTeddyBlank(const TrackerConfig& config, FrameStatus status) {
  const TeddyRun run = runTeddy(nullptr, kBlankFirst, kBlankCount, config);
  EXPECT_EQ(run.statuses.size(), teddyFrames().size());
  for (int i = kBlankFirst;
       i < kBlankFirst + kBlankCount && i < static_cast<int>(run.statuses.size()); ++i) {
    EXPECT_EQ(run.statuses[static_cast<std::size_t>(i)], status) << i;
  }
  std::cout << "[teddy200-blank] ATE RMSE " << run.ate_m * 100 << " cm; relocalized "
            << run.stats.relocalized << ", posed by depth " << run.stats.posed_by_depth << ", lost "
            << run.stats.lost << "\n";
  return run;
}

TEST(TumTeddy, BlankFramesAreLostThenRelocalized) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  TrackerConfig config;
  config.depth_fallback = false;  // no pose from the depth either (the next test has it)
  const TeddyRun run = runTeddyBlank(config, FrameStatus::kLost);
  EXPECT_GE(run.stats.relocalized, 1u);
  EXPECT_LE(run.stats.lost, static_cast<std::size_t>(kBlankCount + 10));
  EXPECT_LE(run.ate_m, 0.05);
}

// The same black frames keep their depth: the static depth poses them (tracking.depth_fallback)
// and none is lost; the run stays within the 3 cm of the whole-run test above.
TEST(TumTeddy, BlankFramesWithDepthArePosedByTheDepthAlone) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  const TeddyRun run = runTeddyBlank(TrackerConfig{}, FrameStatus::kPosedByDepth);
  EXPECT_EQ(run.stats.lost, 0u);
  EXPECT_LE(run.ate_m, 0.03);
}

}  // namespace
}  // namespace dynamap
