#include <gtest/gtest.h>

#include <random>

#include "dynamap/core/camera.hpp"
#include "dynamap/core/tracking/local_ba.hpp"

namespace dynamap {
namespace {

constexpr int kKeyframes = 20;

Eigen::Isometry3d truePose(int k) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.05 * k, 0.01 * k, 0.0);
  T.linear() = Eigen::AngleAxisd(0.01 * k, Eigen::Vector3d::UnitY()).toRotationMatrix();
  return T;
}

/// The tracker's estimate: the true pose with a drift that grows along the path (2 mm and
/// 0.1 degrees per keyframe); keyframe 0 defines the world and is exact.
Eigen::Isometry3d driftedPose(int k) {
  Eigen::Isometry3d drift = Eigen::Isometry3d::Identity();
  drift.translation() = Eigen::Vector3d(0.002 * k, -0.0015 * k, 0.001 * k);
  drift.linear() =
      Eigen::AngleAxisd(0.00175 * k, Eigen::Vector3d(1, 0, 1).normalized()).toRotationMatrix();
  return truePose(k) * drift;
}

/// 400 points on a wall 2.5-3.5 m in front of the path, observed by every keyframe that sees
/// them (pixel noise 0.3 px, depth noise 2 mm), placed in the world from their first
/// observation and its drifted pose, as the tracker places landmarks.
void buildDriftedMap(const PinholeCamera& camera, LocalMap& map) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(-1.2, 2.2), uy(-1.0, 1.0), uz(2.5, 3.5);
  std::normal_distribution<double> px_noise(0.0, 0.3), z_noise(0.0, 0.002);
  std::vector<Eigen::Vector3d> points(400);
  for (auto& p : points) p = Eigen::Vector3d(ux(rng), uy(rng), uz(rng));
  std::vector<std::int64_t> ids(points.size(), -1);
  for (int k = 0; k < kKeyframes; ++k) {
    std::vector<KeyframeObservation> obs;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Eigen::Vector3d p_C = truePose(k).inverse() * points[i];
      const Eigen::Vector2d px(camera.fx * p_C.x() / p_C.z() + camera.cx,
                               camera.fy * p_C.y() / p_C.z() + camera.cy);
      if (px.x() < 0 || px.y() < 0 || px.x() >= camera.width || px.y() >= camera.height) continue;
      const Eigen::Vector2d noisy = px + Eigen::Vector2d(px_noise(rng), px_noise(rng));
      const double depth_m = p_C.z() + z_noise(rng);
      if (ids[i] < 0) {
        const Eigen::Vector3d seen_C = camera.backProject(noisy.x(), noisy.y(), depth_m);
        ids[i] = static_cast<std::int64_t>(map.addLandmark(driftedPose(k) * seen_C, cv::Mat()));
      }
      obs.push_back({static_cast<std::uint64_t>(ids[i]), noisy, depth_m});
    }
    map.addKeyframe(0.1 * k, driftedPose(k), std::move(obs));
  }
}

/// Largest translation error of the keyframes older than the newest `newest` ones.
double worstOldError(const LocalMap& map, int newest) {
  double worst = 0.0;
  for (const auto& kf : map.keyframes()) {
    if (static_cast<int>(kf.id) >= kKeyframes - newest) continue;
    const double e =
        (kf.T_W_C.translation() - truePose(static_cast<int>(kf.id)).translation()).norm();
    worst = std::max(worst, e);
  }
  return worst;
}

TEST(FinalBundleAdjustment, AWindowOverAllKeyframesTakesTheDriftOutOfOldKeyframesToo) {
  const PinholeCamera camera = cameraPreset("freiburg3");
  TrackerConfig config;
  config.ba_window = 8;
  LocalMap local_map, final_map;
  buildDriftedMap(camera, local_map);
  buildDriftedMap(camera, final_map);
  const double before = worstOldError(local_map, config.ba_window);
  ASSERT_GT(before, 0.02);  // keyframe 11 drifted 3.2 cm

  LocalBundleAdjuster local(camera, config, local_map, nullptr);
  local.runOnce();  // the local window: the newest 8 keyframes, the 8 before them fixed
  LocalBundleAdjuster final_ba(camera, config, final_map, nullptr);
  final_ba.runOnce(kKeyframes, 20);  // every keyframe but the first

  // Keyframes older than the local window keep their drift there; the final BA corrects them
  // to the noise level (tolerance 5 mm, 8x below the drift).
  EXPECT_GT(worstOldError(local_map, config.ba_window), 0.8 * before);
  EXPECT_LT(worstOldError(final_map, 0), 0.005);
  EXPECT_EQ(final_ba.takeUpdates().size(), static_cast<std::size_t>(kKeyframes - 1));
}

/// Four keyframes' runs of the BA thread in lockstep (request, then wait for it and write).
void runFourKeyframes(LocalBundleAdjuster& ba) {
  ba.start();
  for (int k = 0; k < 4; ++k) {
    ba.requestRun();
    ba.applyFinished();
  }
  ba.stop();
}

// Named SyntheticTracking.* so that ctest labels it "threaded" (tests/CMakeLists.txt).
TEST(SyntheticTracking, EveryFourthRunOverAllKeyframesTakesOutOldDriftDuringTheRun) {
  const PinholeCamera camera = cameraPreset("freiburg3");
  TrackerConfig config;
  config.ba_window = 8;
  config.ba_lockstep = true;
  config.ba_global_every_keyframes = 4;
  TrackerConfig local_only = config;
  local_only.ba_global_every_keyframes = 0;
  LocalMap periodic_map, local_map;
  buildDriftedMap(camera, periodic_map);
  buildDriftedMap(camera, local_map);
  const double before = worstOldError(local_map, config.ba_window);

  LocalBundleAdjuster periodic(camera, config, periodic_map, nullptr);
  runFourKeyframes(periodic);
  LocalBundleAdjuster local(camera, local_only, local_map, nullptr);
  runFourKeyframes(local);

  // The fourth run took every keyframe: the old ones lose their drift (tolerance 1 cm, 3x below
  // it; 10 iterations, not the 20 of the final BA test); local windows alone leave it.
  EXPECT_LT(worstOldError(periodic_map, 0), 0.01);
  EXPECT_GT(worstOldError(local_map, config.ba_window), 0.8 * before);
  EXPECT_EQ(periodic.runsSinceGlobal(), 0);
  EXPECT_EQ(local.runsSinceGlobal(), 4);
}

}  // namespace
}  // namespace dynamap
