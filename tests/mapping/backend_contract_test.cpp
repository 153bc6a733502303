// Contract test over every backend plugin the registry finds: the synthetic room with a moving
// box (masked) must give a map of the static geometry only, loadable by the libraries' own
// readers, and following pose updates.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <opencv2/imgcodecs.hpp>

#include "dynamap/mapping/ply_io.hpp"
#include "mapping_test_utils.hpp"

#ifdef DYNAMAP_TEST_WITH_PCL
#include <pcl/PolygonMesh.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#endif
#ifdef DYNAMAP_TEST_WITH_OPENVDB
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#endif
#ifdef DYNAMAP_TEST_WITH_OCTOMAP
#include <octomap/AbstractOcTree.h>
#include <octomap/OcTree.h>
#endif

namespace dynamap::test {
namespace {

constexpr int kFrames = 6;
namespace fs = std::filesystem;

std::vector<std::string> backendNames() { return BackendRegistry::scan({pluginDir()}).names(); }

class BackendContract : public ::testing::TestWithParam<std::string> {
 protected:
  std::unique_ptr<MapBackend> create() const {
    return BackendRegistry::scan({pluginDir()}).create(GetParam(), backendCase(GetParam()).params);
  }
};

std::size_t countInsideMoving(const std::vector<Eigen::Vector3f>& pts, double margin) {
  std::size_t n = 0;
  for (const auto& p : pts) {
    for (int k = 0; k < kFrames; ++k) {
      if (SyntheticScene::movingBox(k).contains(p.cast<double>(), margin)) {
        ++n;
        break;
      }
    }
  }
  return n;
}

/// The text OBJ holds the binary PLY's mesh, each number as printf's "%.5f" (position) and
/// "%.4f" (colour / 255) write it, faces 1-based.
void expectObjMatchesPly(const fs::path& dir) {
  const PlyData mesh = readPly((dir / "mesh.ply").string(), true);
  std::ifstream obj(dir / "mesh.obj");
  std::string line;
  std::size_t v = 0, f = 0;
  char want[256];
  while (std::getline(obj, line)) {
    if (line.rfind("v ", 0) == 0) {
      ASSERT_LT(v, mesh.vertices.size());
      const auto& p = mesh.vertices[v];
      const auto& c = mesh.colors[v];
      std::snprintf(want, sizeof(want), "v %.5f %.5f %.5f %.4f %.4f %.4f", p.x(), p.y(), p.z(),
                    c[0] / 255.0, c[1] / 255.0, c[2] / 255.0);
      ASSERT_EQ(line, want) << "vertex " << v;
      ++v;
    } else if (line.rfind("f ", 0) == 0) {
      ASSERT_LT(f, mesh.triangles.size());
      const auto& t = mesh.triangles[f];
      std::snprintf(want, sizeof(want), "f %u %u %u", t[0] + 1, t[1] + 1, t[2] + 1);
      ASSERT_EQ(line, want) << "face " << f;
      ++f;
    }
  }
  EXPECT_EQ(v, mesh.vertices.size());
  EXPECT_EQ(f, mesh.triangles.size());
  EXPECT_GT(f, 0u);
}

void expectExportsLoad(const std::string& name, const fs::path& dir) {
  const std::map<std::string, std::vector<std::string>> expected = {
      {"points", {"cloud.ply", "cloud.pcd"}},
      {"pcl_voxel", {"cloud.ply", "cloud.pcd"}},
      {"vdb_tsdf", {"mesh.ply", "mesh.obj", "tsdf.vdb", "tsdf.vdb.crc32"}},
      {"octomap", {"map.bt", "map.ot", "grid.pgm", "grid.yaml", "cloud.ply"}},
  };
  if (expected.count(name)) {
    for (const auto& f : expected.at(name)) EXPECT_TRUE(fs::exists(dir / f)) << f;
  }
  if (fs::exists(dir / "mesh.obj") && fs::exists(dir / "mesh.ply")) expectObjMatchesPly(dir);
  for (const auto& e : fs::directory_iterator(dir)) {  // no temporary left behind
    EXPECT_NE(e.path().filename().string().front(), '.') << e.path();
  }
#ifdef DYNAMAP_TEST_WITH_PCL
  if (fs::exists(dir / "cloud.ply")) {
    pcl::PCLPointCloud2 cloud;
    EXPECT_EQ(pcl::io::loadPLYFile((dir / "cloud.ply").string(), cloud), 0);
    EXPECT_GT(cloud.width * cloud.height, 0u);
  }
  if (fs::exists(dir / "cloud.pcd")) {
    pcl::PCLPointCloud2 cloud;
    EXPECT_EQ(pcl::io::loadPCDFile((dir / "cloud.pcd").string(), cloud), 0);
    EXPECT_GT(cloud.width * cloud.height, 0u);
  }
  if (fs::exists(dir / "mesh.ply")) {
    pcl::PolygonMesh mesh;
    EXPECT_EQ(pcl::io::loadPLYFile((dir / "mesh.ply").string(), mesh), 0);
    EXPECT_GT(mesh.polygons.size(), 0u);
  }
#endif
#ifdef DYNAMAP_TEST_WITH_OPENVDB
  if (fs::exists(dir / "tsdf.vdb")) {
    openvdb::initialize();
    openvdb::io::File file((dir / "tsdf.vdb").string());
    file.open();
    EXPECT_TRUE(file.hasGrid("tsdf"));
    EXPECT_TRUE(file.hasGrid("weight"));
    EXPECT_GT(file.readGrid("tsdf")->activeVoxelCount(), 0u);
    file.close();
  }
#endif
#ifdef DYNAMAP_TEST_WITH_OCTOMAP
  if (fs::exists(dir / "map.bt")) {
    octomap::OcTree tree(0.1);
    EXPECT_TRUE(tree.readBinary((dir / "map.bt").string()));
    EXPECT_GT(tree.getNumLeafNodes(), 0u);
  }
  if (fs::exists(dir / "map.ot")) {
    std::unique_ptr<octomap::AbstractOcTree> tree(
        octomap::AbstractOcTree::read((dir / "map.ot").string()));
    ASSERT_NE(tree, nullptr);
    EXPECT_EQ(tree->getTreeType(), "OcTree");
  }
#endif
  if (fs::exists(dir / "grid.pgm")) {
    const cv::Mat grid = cv::imread((dir / "grid.pgm").string(), cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(grid.empty());
    EXPECT_GT(cv::countNonZero(grid == 0), 0) << "no occupied cell in the 2D grid";
    EXPECT_GT(cv::countNonZero(grid == 254), 0) << "no free cell in the 2D grid";
    std::ifstream yaml(dir / "grid.yaml");
    const std::string text((std::istreambuf_iterator<char>(yaml)), {});
    EXPECT_NE(text.find("image: grid.pgm"), std::string::npos);
    EXPECT_NE(text.find("resolution: 0.05"), std::string::npos);
  }
}

TEST_P(BackendContract, MapsStaticGeometryOnlyAndExportsLoad) {
  const double tol = backendCase(GetParam()).voxel_m;
  const fs::path dir = freshTempDir("contract_" + GetParam());
  const MapStats stats =
      buildSyntheticMap(create(), kFrames, true, Eigen::Vector3d::Zero(), dir.string());
  EXPECT_EQ(stats.keyframes, static_cast<std::size_t>(kFrames));
  EXPECT_GT(stats.elements, 0u);
  const auto pts = readPly(scoredFile(dir.string())).vertices;
  ASSERT_GT(pts.size(), 200u);
  const SyntheticScene scene;
  std::size_t within = 0, on_box_top = 0;
  double worst = 0.0;
  for (const auto& p : pts) {
    const double d = scene.staticDistance(p.cast<double>());
    worst = std::max(worst, d);
    within += d <= tol + 1e-3 ? 1 : 0;
    on_box_top +=
        (std::fabs(p.z() - 0.4) <= tol && p.x() > 0.35 && p.x() < 0.65 && std::fabs(p.y()) < 0.15)
            ? 1
            : 0;
  }
  // Every element within one voxel of the truth, allowing 1 % at corners; none beyond 3 voxels.
  EXPECT_GE(static_cast<double>(within) / pts.size(), 0.99) << "worst " << worst;
  EXPECT_LE(worst, 3 * tol + 1e-3);
  EXPECT_GT(on_box_top, 3u) << "the static box is missing";
  EXPECT_EQ(countInsideMoving(pts, tol), 0u) << "the masked moving box leaked into the map";
  expectExportsLoad(GetParam(), dir);
}

TEST_P(BackendContract, PoseUpdatesMoveTheMap) {
  const double tol = backendCase(GetParam()).voxel_m;
  const Eigen::Vector3d shift(0.3, 0.2, 0.15);
  const fs::path dir = freshTempDir("pose_" + GetParam());
  buildSyntheticMap(create(), kFrames, true, shift, dir.string());
  const auto pts = readPly(scoredFile(dir.string())).vertices;
  ASSERT_GT(pts.size(), 200u);
  const SyntheticScene scene;
  std::size_t at_new = 0, at_old = 0;
  for (const auto& p : pts) {
    at_new += scene.staticDistance(p.cast<double>(), shift) <= tol + 1e-3 ? 1 : 0;
    at_old += scene.staticDistance(p.cast<double>()) <= tol + 1e-3 ? 1 : 0;
  }
  EXPECT_GE(static_cast<double>(at_new) / pts.size(), 0.98);
  EXPECT_LE(static_cast<double>(at_old) / pts.size(), 0.5);
}

TEST_P(BackendContract, RejectsUnknownParameterNamingTheKey) {
  const auto registry = BackendRegistry::scan({pluginDir()});
  try {
    registry.create(GetParam(), {{"no_such_key", "1"}});
    FAIL() << "no exception";
  } catch (const MappingError& e) {
    EXPECT_NE(std::string(e.what()).find("mapping.params." + GetParam() + ".no_such_key"),
              std::string::npos)
        << e.what();
  }
}

// pcl_voxel keeps the newest resident_keyframes in RAM and the others in a spill file: the map
// it exports after pose updates is the same either way.
TEST(PclVoxelSpill, SpilledKeyframesGiveTheSameMapAsResidentOnes) {
  const auto registry = BackendRegistry::scan({pluginDir()});
  const auto names = registry.names();
  if (std::find(names.begin(), names.end(), "pcl_voxel") == names.end()) {
    GTEST_SKIP() << "pcl_voxel not built";
  }
  const Eigen::Vector3d shift(0.3, 0.2, 0.15);
  std::vector<PlyData> maps;
  for (const char* resident : {"0", "1"}) {
    BackendParams params = backendCase("pcl_voxel").params;
    params["resident_keyframes"] = resident;
    const fs::path dir = freshTempDir(std::string("spill_") + resident);
    const MapStats stats =
        buildSyntheticMap(registry.create("pcl_voxel", params), kFrames, true, shift, dir.string());
    EXPECT_EQ(stats.keyframes, static_cast<std::size_t>(kFrames));
    maps.push_back(readPly((dir / "cloud.ply").string()));
  }
  ASSERT_GT(maps[0].vertices.size(), 200u);
  ASSERT_EQ(maps[0].vertices.size(), maps[1].vertices.size());
  for (std::size_t i = 0; i < maps[0].vertices.size(); ++i) {
    ASSERT_LE((maps[0].vertices[i] - maps[1].vertices[i]).norm(), 1e-6f) << "point " << i;
    ASSERT_EQ(maps[0].colors[i], maps[1].colors[i]) << "point " << i;
  }
}

INSTANTIATE_TEST_SUITE_P(AllBackends, BackendContract, ::testing::ValuesIn(backendNames()),
                         [](const auto& info) { return info.param; });
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(BackendContract);

// Shows the contract can fail: without the mask the moving box does end up in the map (with the
// visibility pass off: it would remove the box, see visibility_test.cpp).
TEST(BackendContractSanity, UnmaskedMovingBoxLeaks) {
  const auto registry = BackendRegistry::scan({pluginDir()});
  if (registry.pluginPath("points").empty()) GTEST_SKIP() << "points backend not built";
  const fs::path dir = freshTempDir("contract_unmasked");
  StaticPointsOptions options;
  options.visibility.enabled = false;
  buildSyntheticMap(registry.create("points", {}), kFrames, false, Eigen::Vector3d::Zero(),
                    dir.string(), options);
  EXPECT_GT(countInsideMoving(readPly((dir / "cloud.ply").string()).vertices, 0.01), 100u);
}

}  // namespace
}  // namespace dynamap::test
