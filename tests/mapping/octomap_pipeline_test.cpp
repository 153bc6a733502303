// The octomap backend casts one keyframe's rays on another thread while it writes the previous
// keyframe's cells into its tree: the map must be exactly OctoMap's own insertPointCloud's.
#ifdef DYNAMAP_TEST_WITH_OCTOMAP

#include <filesystem>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include "dynamap/mapping/static_points.hpp"
#include "mapping_test_utils.hpp"

namespace dynamap {
namespace {

namespace fs = std::filesystem;

TEST(OctomapBackend, PipelinedRayCastingGivesInsertPointCloudsMap) {
  const auto registry = BackendRegistry::scan({test::pluginDir()});
  if (registry.pluginPath("octomap").empty()) GTEST_SKIP() << "octomap backend not built";
  const double res = 0.05;
  auto backend = registry.create("octomap", {{"resolution_m", "0.05"}});
  octomap::OcTree reference(res);
  reference.setProbHit(0.7);
  reference.setProbMiss(0.4);
  reference.setClampingThresMin(0.12);
  reference.setClampingThresMax(0.97);

  const test::SyntheticScene scene;
  const PinholeCamera cam = test::SyntheticScene::camera();
  const int n = 8;
  for (int k = 0; k < n; ++k) {
    const test::SyntheticFrame f = scene.render(k, n);
    StaticPointsOptions options;
    options.stride = 2;
    const StaticPoints sp = extractStaticPoints(cam, f.bgr, f.depth_m, f.mask, options);
    const auto& points = sp.points_C;
    backend->integrate(
        keyframeView(static_cast<std::uint64_t>(k), 0.1 * k, f.T_W_C, cam, f.bgr, sp));
    if (k == n / 2) {  // a reader in between takes the cells still in flight
      EXPECT_EQ(backend->stats().keyframes, static_cast<std::size_t>(k + 1));
    }
    // OctoMap itself, on the distinct voxel centres the backend reduces each keyframe to.
    octomap::Pointcloud cloud;
    octomap::KeySet seen;
    for (const auto& p_C : points) {
      const Eigen::Vector3f p = f.T_W_C.cast<float>() * p_C;
      octomap::OcTreeKey key;
      if (reference.coordToKeyChecked(p.x(), p.y(), p.z(), key) && seen.insert(key).second)
        cloud.push_back(reference.keyToCoord(key));
    }
    const Eigen::Vector3d o = f.T_W_C.translation();
    reference.insertPointCloud(cloud, octomap::point3d(o.x(), o.y(), o.z()), -1.0, true, false);
  }
  reference.updateInnerOccupancy();
  const fs::path dir = fs::temp_directory_path() / "dynamap_octomap_pipeline";
  fs::remove_all(dir);
  backend->exportMap(dir.string());
  octomap::OcTree exported(res);
  ASSERT_TRUE(exported.readBinary((dir / "map.bt").string()));
  reference.toMaxLikelihood();
  reference.prune();
  // map.bt holds occupancy bits: the same cells, free and occupied, both ways (either tree may
  // hold a region as one pruned node).
  const auto sameCells = [](const octomap::OcTree& a, const octomap::OcTree& b) {
    std::size_t compared = 0, differ = 0;
    for (auto it = a.begin_leafs(), end = a.end_leafs(); it != end; ++it, ++compared) {
      const octomap::OcTreeNode* node = b.search(it.getKey(), it.getDepth());
      differ += node == nullptr || b.isNodeOccupied(node) != a.isNodeOccupied(*it);
    }
    EXPECT_EQ(differ, 0u) << "of " << compared;
    return compared;
  };
  EXPECT_GT(sameCells(reference, exported), 1000u);
  EXPECT_GT(sameCells(exported, reference), 1000u);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace dynamap

#endif  // DYNAMAP_TEST_WITH_OCTOMAP
