// Save and reload (issue 47, point 4): a second run started in a saved map relocalizes in it
// within the first frames, reports poses in the saved map's frame, reuses its keyframes and
// extends its dense map, whichever backend made it; a bad map is one MapFileError before
// anything runs.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "dynamap/mapping/backend_registry.hpp"
#include "dynamap/mapping/ply_io.hpp"
#include "dynamap/system.hpp"
#include "dynamap/system/map_store.hpp"
#include "synthetic_scene.hpp"
#include "test_paths.hpp"

namespace dynamap::saved_map_test {
namespace {

constexpr int kFrames = 60;
constexpr double kPeriodS = 1.0 / 30.0;

AppConfig savedMapConfig() {
  AppConfig config;
  config.dynamic.mode = "off";
  config.mapping.backend = "pcl_voxel";  // the default backend
  return config;
}

/// Camera i of a slow walk to the right and forward while turning (truth, scene frame).
Eigen::Isometry3d walkPose(int i) {
  const double s = static_cast<double>(i) / (kFrames - 1);
  return test::cameraPose({0.3 * s, 0.05 * std::sin(3.0 * s), 0.25 * s}, -8.0 + 16.0 * s, 3.0);
}

struct RunOutcome {
  std::vector<FrameStatus> statuses;
  std::vector<double> errors_m;  ///< per frame with a pose: against the truth in frame 0's frame
  SystemCounts counts;
};

/// Tracks the walk's frames in `order`; errors against run 1's world (camera of frame 0).
RunOutcome runWalk(System& system, const test::SyntheticScene& scene, const std::vector<int>& order,
                   double t0_s) {
  RunOutcome out;
  const Eigen::Isometry3d T_scene_W = walkPose(0);
  for (std::size_t j = 0; j < order.size(); ++j) {
    const int i = order[j];
    const auto r = scene.render(walkPose(i), 0.0);
    RgbdFrame frame;
    frame.index = j;
    frame.timestamp_s = t0_s + j * kPeriodS;
    frame.bgr = r.bgr;
    frame.depth_m = r.depth_m;
    system.track(frame);
  }
  system.finish();
  out.statuses = system.frameStatuses();
  const auto trajectory = system.trajectory();
  for (std::size_t j = 0; j < trajectory.size(); ++j) {
    if (out.statuses[j] == FrameStatus::kLost) continue;
    const Eigen::Isometry3d truth = T_scene_W.inverse() * walkPose(order[j]);
    out.errors_m.push_back((trajectory[j].T_W_C.translation() - truth.translation()).norm());
  }
  out.counts = system.counts();
  return out;
}

double rms(const std::vector<double>& v) {
  double sum2 = 0.0;
  for (const double e : v) sum2 += e * e;
  return v.empty() ? INFINITY : std::sqrt(sum2 / v.size());
}

std::vector<int> walkFrames(bool forward) {
  std::vector<int> order;
  for (int i = 0; i < kFrames; ++i) order.push_back(forward ? i : kFrames - 1 - i);
  return order;
}

TEST(SavedMap, ReloadRelocalizesInTheSavedFrameAndExtendsTheMap) {
  const AppConfig config = savedMapConfig();
  test::SyntheticScene scene(config.resolvedCamera(), 21);
  scene.addDefaultRoom();
  const auto dir = test::freshTempDir("saved_map_reload");
  const std::vector<int> forward = walkFrames(true), backward = walkFrames(false);

  System first(config);
  const RunOutcome run1 = runWalk(first, scene, forward, 0.0);
  first.saveMap(dir.string());
  ASSERT_TRUE(std::filesystem::exists(dir / kMapStoreFile));
  ASSERT_TRUE(std::filesystem::exists(dir / "map" / "cloud.ply"));
  ASSERT_GT(run1.counts.keyframes, 1u);

  SystemOptions options;
  options.load_map_dir = dir.string();
  System second(config, std::move(options));
  const RunOutcome run2 = runWalk(second, scene, backward, 100.0);  // a later run
  std::size_t first_posed = 0;
  while (first_posed < run2.statuses.size() && run2.statuses[first_posed] == FrameStatus::kLost) {
    ++first_posed;
  }
  std::printf(
      "run 1: %zu keyframes, %zu voxels, RMS %.2f mm; run 2: posed from frame %zu, "
      "RMS %.2f mm, %zu new keyframes, %zu voxels\n",
      run1.counts.keyframes, run1.counts.map_elements, 1e3 * rms(run1.errors_m), first_posed,
      1e3 * rms(run2.errors_m), run2.counts.keyframes, run2.counts.map_elements);
  EXPECT_EQ(run2.counts.loaded_keyframes, run1.counts.keyframes);
  EXPECT_NEAR(static_cast<double>(run2.counts.loaded_map_elements), run1.counts.map_elements,
              0.02 * run1.counts.map_elements);
  EXPECT_LE(first_posed, 2u);                // relocalized in the first frames
  EXPECT_EQ(run2.counts.lost, first_posed);  // and never lost after that
  // In run 1's frame without any alignment: as accurate as run 1 itself (< 1 cm RMS there).
  EXPECT_LT(rms(run2.errors_m), 0.01);
  // The same path backward: the saved keyframes are reused, few new ones.
  EXPECT_LE(run2.counts.keyframes, run1.counts.keyframes / 5 + 1);
  // The map is extended, not rebuilt (no new keyframe here: without the loaded points it would
  // be empty): run 1's voxels and few new ones (same room). A saved voxel centroid may round
  // into the next voxel: the synthetic walls lie on voxel faces (2 % allowed).
  EXPECT_GE(run2.counts.map_elements, 0.98 * run1.counts.map_elements);
  EXPECT_LE(run2.counts.map_elements, 1.15 * run1.counts.map_elements);
}

TEST(SavedMap, BadMapIsOneErrorBeforeAnythingRuns) {
  const auto dir = test::freshTempDir("saved_map_bad");
  SystemOptions options;
  options.load_map_dir = dir.string();  // empty folder: no map.sqlite
  try {
    System system(savedMapConfig(), std::move(options));
    FAIL() << "a folder without a map was accepted";
  } catch (const MapFileError& e) {
    EXPECT_NE(std::string(e.what()).find((dir / kMapStoreFile).string()), std::string::npos)
        << e.what();
  }
}

/// The exported map's vertices: the mesh's (vdb_tsdf) or the cloud's (octomap: cell centres).
std::size_t exportedVertices(const std::filesystem::path& dir) {
  const auto mesh = dir / "mesh.ply";
  return readPly((std::filesystem::exists(mesh) ? mesh : dir / "cloud.ply").string())
      .vertices.size();
}

/// The volumetric backends start from their saved volume (tsdf.vdb, map.ot), not from nothing.
class SavedMapVolume : public ::testing::TestWithParam<std::string> {
 protected:
  AppConfig config() const {
    AppConfig c = savedMapConfig();
    c.mapping.backend = GetParam();
    // Coarser than the defaults (0.02 / 0.03 m): the test's runtime is the ray casting's.
    c.mapping.params["vdb_tsdf.voxel_size_m"] = "0.04";
    c.mapping.params["octomap.resolution_m"] = "0.06";
    return c;
  }
};

TEST_P(SavedMapVolume, ReloadStartsFromTheSavedVolume) {
  const AppConfig config = this->config();
  test::SyntheticScene scene(config.resolvedCamera(), 21);
  scene.addDefaultRoom();
  const auto dir = test::freshTempDir("saved_volume_" + GetParam());
  System first(config);
  const RunOutcome run1 = runWalk(first, scene, walkFrames(true), 0.0);
  first.saveMap(dir.string());
  const std::size_t saved = exportedVertices(dir / "map");
  ASSERT_GT(saved, 1000u);

  SystemOptions unchanged_options;  // reloaded, no frame, exported again
  unchanged_options.load_map_dir = dir.string();
  System unchanged(config, std::move(unchanged_options));
  unchanged.exportMap((dir / "again").string());
  const std::size_t again = exportedVertices(dir / "again");

  SystemOptions options;  // the walk backward on the saved map
  options.load_map_dir = dir.string();
  System second(config, std::move(options));
  const RunOutcome run2 = runWalk(second, scene, walkFrames(false), 100.0);
  std::printf(
      "%s: run 1 %zu elements, %zu exported; reloaded %zu, %zu; run 2 %zu (%zu new "
      "keyframes)\n",
      GetParam().c_str(), run1.counts.map_elements, saved, unchanged.counts().map_elements, again,
      run2.counts.map_elements, run2.counts.keyframes);
  EXPECT_EQ(unchanged.counts().mapped_keyframes, 0u);  // the saved volume is no keyframe
  EXPECT_EQ(unchanged.counts().loaded_map_elements, run1.counts.map_elements);
  EXPECT_NEAR(static_cast<double>(again), saved, 0.01 * saved);  // the same surface / cells
  // The walk backward sees what run 1 saw: run 1's map and few new elements (without the saved
  // volume: only the few new keyframes' view).
  EXPECT_GE(run2.counts.map_elements, 0.98 * run1.counts.map_elements);
  EXPECT_LE(run2.counts.map_elements, 1.15 * run1.counts.map_elements);
}

TEST_P(SavedMapVolume, CorruptVolumeIsOneErrorNamingTheFileBeforeAnythingRuns) {
  const AppConfig config = this->config();
  test::SyntheticScene scene(config.resolvedCamera(), 21);
  scene.addDefaultRoom();
  const auto dir = test::freshTempDir("saved_volume_bad_" + GetParam());
  System first(config);
  runWalk(first, scene, {0, 1, 2, 3, 4, 5}, 0.0);
  first.saveMap(dir.string());
  const auto file = dir / "map" / (GetParam() == "vdb_tsdf" ? "tsdf.vdb" : "map.ot");
  std::filesystem::resize_file(file, std::filesystem::file_size(file) / 2);
  SystemOptions options;
  options.load_map_dir = dir.string();
  try {
    System system(config, std::move(options));
    FAIL() << "a truncated " << file << " was accepted";
  } catch (const MapFileError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(file.string() + ": ", 0), 0u) << e.what();
  }
}

std::vector<std::string> volumeBackends() {
  std::vector<std::string> out;
  for (const auto& name : BackendRegistry::scan({(test::binaryDir() / "lib").string()}).names()) {
    if (name == "vdb_tsdf" || name == "octomap") out.push_back(name);
  }
  return out;
}

INSTANTIATE_TEST_SUITE_P(Volumes, SavedMapVolume, ::testing::ValuesIn(volumeBackends()),
                         [](const auto& info) { return info.param; });
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(SavedMapVolume);

}  // namespace
}  // namespace dynamap::saved_map_test
