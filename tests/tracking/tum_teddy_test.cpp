#include <gtest/gtest.h>

#include <iostream>
#include <map>

#include <opencv2/imgcodecs.hpp>

#include "dynamap/core/tracker.hpp"
#include "test_paths.hpp"
#include "tracking_test_utils.hpp"

namespace dynamap {
namespace {

constexpr std::size_t kRgbEntries = 200;  // the first 200 colour images (193 associate)
constexpr double kMaxDtS = 0.02;

/// The associated colour/depth frames among the first kRgbEntries colour images (depth by
/// nearest timestamp within kMaxDtS).
std::vector<RgbdFrame> loadTeddy(const std::filesystem::path& dir) {
  const auto rgb = test::readTumList((dir / "rgb.txt").string());
  std::map<double, std::string> depth;
  for (const auto& e : test::readTumList((dir / "depth.txt").string()))
    depth[e.timestamp_s] = e.path;
  std::vector<RgbdFrame> frames;
  for (std::size_t k = 0; k < std::min(rgb.size(), kRgbEntries); ++k) {
    const auto& e = rgb[k];
    const std::string* depth_path = test::nearest(depth, e.timestamp_s, kMaxDtS);
    if (!depth_path) continue;
    RgbdFrame f;
    f.index = frames.size();
    f.timestamp_s = e.timestamp_s;
    f.bgr = cv::imread((dir / e.path).string(), cv::IMREAD_COLOR);
    const cv::Mat raw = cv::imread((dir / *depth_path).string(), cv::IMREAD_UNCHANGED);
    if (f.bgr.empty() || raw.empty()) continue;
    raw.convertTo(f.depth_m, CV_32F, 1.0 / 5000.0);
    frames.push_back(std::move(f));
  }
  return frames;
}

// Measured (Release, 2 cores, BA thread on): see the printed line; the target is 2 cm, the
// assertion keeps a margin for machine-to-machine differences in thread timing.
TEST(TumTeddy, First200FramesAllPosedWithLowAte) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  const auto dir = test::sharedData() / "tum" / "rgbd_dataset_freiburg3_teddy";
  const std::vector<RgbdFrame> frames = loadTeddy(dir);
  ASSERT_GE(frames.size(), 190u);
  const std::size_t n = frames.size();
  const auto gt = test::readTumGroundTruth((dir / "groundtruth.txt").string());

  TimingRecorder timings;
  Tracker tracker(cameraPreset("freiburg3"), TrackerConfig{}, &timings);
  for (const auto& f : frames) tracker.track(f);
  tracker.finish();

  const auto traj = tracker.finalTrajectory();
  const auto statuses = tracker.frameStatuses();
  ASSERT_EQ(traj.size(), n);
  std::vector<Eigen::Vector3d> est, ref;
  std::size_t posed = 0;
  for (std::size_t i = 0; i < traj.size(); ++i) {
    if (statuses[i] != FrameStatus::kLost) ++posed;
    const Eigen::Isometry3d* truth = test::nearest(gt, traj[i].first, kMaxDtS);
    if (!truth) continue;
    est.push_back(traj[i].second.translation());
    ref.push_back(truth->translation());
  }
  const double ate = test::ateRmseAligned(est, ref);
  const TrackerStats s = tracker.stats();
  std::cout << "[teddy200] ATE RMSE " << ate * 100 << " cm over " << est.size()
            << " gt-matched frames; tracked share "
            << static_cast<double>(posed) / static_cast<double>(n) << " (tracked " << s.tracked
            << ", relocalized " << s.relocalized << ", lost " << s.lost << "), keyframes "
            << s.keyframes << "\n";
  for (const auto& [stage, st] : timings.allStats()) {
    std::cout << "[teddy200] " << stage << ": n=" << st.count << " median " << st.median_ms
              << " ms, p95 " << st.p95_ms << " ms, max " << st.max_ms << " ms\n";
  }
  EXPECT_EQ(posed, n);
  EXPECT_GT(est.size(), n * 9 / 10);
  EXPECT_LE(ate, 0.03);
}

}  // namespace
}  // namespace dynamap
