// The online map (issue 47): keyframes reach the backend during the run, so a snapshot in the
// middle of a run already holds most of what the final map holds for the keyframes so far.
#include <cstdio>
#include <filesystem>

#include <gtest/gtest.h>

#include "dynamap/system.hpp"
#include "synthetic_scene.hpp"
#include "test_paths.hpp"

namespace dynamap {
namespace {

constexpr int kFrames = 60;
constexpr double kPeriodS = 0.1;  // every frame a keyframe (given poses): 10 keyframes a second

AppConfig onlineConfig() {
  AppConfig config;
  config.dynamic.mode = "off";
  config.mapping.backend = "pcl_voxel";  // the default backend: elements are voxels
  return config;
}

/// Camera k of a pan across the synthetic room (the same path whatever the frames fed).
Eigen::Isometry3d panPose(int k) {
  const double yaw_deg = -25.0 + 50.0 * k / (kFrames - 1);
  return test::cameraPose({0.1 * k / kFrames, 0.0, 0.2}, yaw_deg, 5.0);
}

/// Feeds frames [0, frames) with given poses; `snapshot` is called after each.
template <typename Fn>
void feed(System& system, const test::SyntheticScene& scene, int frames, const Fn& snapshot) {
  for (int k = 0; k < frames; ++k) {
    const auto r = scene.render(panPose(k), k * kPeriodS);
    RgbdFrame frame;
    frame.index = static_cast<std::size_t>(k);
    frame.timestamp_s = k * kPeriodS;
    frame.bgr = r.bgr;
    frame.depth_m = r.depth_m;
    system.mapWithPose(frame, panPose(k), cv::Mat());
    snapshot(k);
  }
}

TEST(OnlineMap, MidRunSnapshotHoldsMostOfTheFinalMapOfItsKeyframes) {
  const AppConfig config = onlineConfig();
  test::SyntheticScene scene(config.resolvedCamera(), 5);
  scene.addDefaultRoom();
  constexpr int kMiddle = kFrames / 2;
  // The run, with a snapshot after the middle frame.
  SystemOptions options;
  options.given_poses = true;
  System run(config, std::move(options));
  SystemCounts mid;
  const auto dir = test::freshTempDir("online_map_mid");
  feed(run, scene, kFrames, [&](int k) {
    if (k + 1 != kMiddle) return;
    run.exportMapSnapshot(dir.string());
    mid = run.counts();
  });
  EXPECT_TRUE(std::filesystem::exists(dir / "cloud.ply"));
  EXPECT_GT(mid.mapped_keyframes, 0u);
  // The final map of the first half's keyframes: a run of those frames only, finished.
  SystemOptions half_options;
  half_options.given_poses = true;
  System half(config, std::move(half_options));
  feed(half, scene, kMiddle, [](int) {});
  half.finish();
  const SystemCounts final_half = half.counts();
  ASSERT_EQ(final_half.mapped_keyframes, static_cast<std::size_t>(kMiddle));
  ASSERT_GT(final_half.map_elements, 1000u);
  std::printf("mid-run: %zu of %d keyframes mapped, %zu voxels; those frames finished: %zu\n",
              mid.mapped_keyframes, kMiddle, mid.map_elements, final_half.map_elements);
  EXPECT_GE(mid.map_elements, 0.8 * final_half.map_elements)
      << mid.mapped_keyframes << " keyframes mapped mid-run";
  run.finish();
  EXPECT_EQ(run.counts().mapped_keyframes, static_cast<std::size_t>(kFrames));
}

}  // namespace
}  // namespace dynamap
