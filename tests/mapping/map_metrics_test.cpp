#include <gtest/gtest.h>

#include <fstream>
#include <random>

#include <opencv2/imgcodecs.hpp>

#include "dynamap/mapping/ply_io.hpp"
#include "dynamap/mapping/static_points.hpp"
#include "map_metrics.hpp"
#include "test_paths.hpp"
#include "trajectory_io.hpp"
#include "tum_dataset.hpp"

namespace dynamap::test {
namespace {

std::vector<Eigen::Vector3f> planeZ(float z, float step) {  // 1 m x 1 m at height z
  std::vector<Eigen::Vector3f> out;
  for (float x = 0; x < 1.0f; x += step)
    for (float y = 0; y < 1.0f; y += step) out.emplace_back(x, y, z);
  return out;
}

ReferenceClouds makeRefs(std::vector<Eigen::Vector3f> stat, std::vector<Eigen::Vector3f> dyn) {
  ReferenceClouds r;
  r.static_points = stat;
  r.static_ref = std::make_shared<PointIndex>(std::move(stat));
  r.dynamic_ref = std::make_shared<PointIndex>(std::move(dyn));
  return r;
}

TEST(PointIndex, MatchesBruteForce) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1, 1);
  std::vector<Eigen::Vector3f> pts(2000);
  for (auto& p : pts) p = {u(rng), u(rng), u(rng)};
  const PointIndex index(pts);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3f q(u(rng) * 2, u(rng) * 2, u(rng) * 2);
    float best = 1e9f;
    for (const auto& p : pts) best = std::min(best, (p - q).norm());
    EXPECT_NEAR(index.nearestDistance(q), best, 1e-6f);
    const float bounded = index.nearestDistance(q, 0.1f);
    if (best <= 0.099f) {
      EXPECT_NEAR(bounded, best, 1e-6f);
    } else if (best > 0.101f) {
      EXPECT_TRUE(std::isinf(bounded));
    }
  }
}

// A dense surface (a wall with a step) and queries from 0 to 3 m off it: the geometry of the
// maps' far-off points, where the search must prune by its nodes' boxes to stay fast.
TEST(PointIndex, MatchesBruteForceOnASurfaceFromAfar) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<Eigen::Vector3f> pts(20000);
  for (auto& p : pts) {
    const float x = 2 * u(rng), y = 2 * u(rng);
    p = {x, y, x > 1.0f ? 0.3f : 0.0f};
  }
  const PointIndex index(pts);
  for (int i = 0; i < 300; ++i) {
    const Eigen::Vector3f q(4 * u(rng) - 1, 4 * u(rng) - 1, 3 * u(rng) - 0.1f);
    float best = 1e9f;
    for (const auto& p : pts) best = std::min(best, (p - q).norm());
    EXPECT_EQ(index.nearestDistance(q), best) << q.transpose();
    EXPECT_EQ(index.nearestDistance(q, best + 0.09f), best);
  }
}

TEST(MapMetrics, DefinitionsOnASyntheticPlane) {
  const auto refs = makeRefs(planeZ(0.0f, 0.01f), planeZ(0.5f, 0.01f));
  const MapMetrics same = computeMapMetrics(planeZ(0.0f, 0.01f), refs);
  EXPECT_NEAR(same.precision, 1.0, 1e-9);
  EXPECT_NEAR(same.completeness, 1.0, 1e-9);
  EXPECT_NEAR(same.ghost_ratio, 0.0, 1e-9);
  EXPECT_LT(same.accuracy_mean_m, 0.006);  // centroids of 1 cm voxels

  // Half the map on the static plane, half a ghost on the dynamic one; the map covers the
  // static plane's half x < 0.5.
  std::vector<Eigen::Vector3f> map;
  for (const auto& p : planeZ(0.0f, 0.01f))
    if (p.x() < 0.5f) map.push_back(p);
  const std::size_t n_static = map.size();
  for (const auto& p : planeZ(0.5f, 0.01f))
    if (p.x() < 0.5f) map.push_back(p);
  const MapMetrics m = computeMapMetrics(map, refs);
  EXPECT_NEAR(m.precision, static_cast<double>(n_static) / map.size(), 0.02);
  EXPECT_NEAR(m.ghost_ratio, 1.0 - m.precision, 0.02);
  EXPECT_NEAR(m.completeness, 0.55, 0.03);  // x < 0.5 plus the 5 cm margin
  EXPECT_NEAR(m.accuracy_mean_m, 0.25, 0.02);
  EXPECT_NEAR(m.fscore, 2 * m.precision * m.completeness / (m.precision + m.completeness), 1e-9);

  // The rigid transform is applied before scoring.
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation().z() = -0.2;
  const MapMetrics moved = computeMapMetrics(planeZ(0.2f, 0.01f), refs, T);
  EXPECT_NEAR(moved.precision, 1.0, 1e-9);
}

// Ghost fragments: 26-connected groups of >= 50 ghost points on the 1 cm grid.
TEST(MapMetrics, GhostFragmentsAreConnectedGroupsOfAtLeast50Points) {
  const auto refs = makeRefs(planeZ(0.0f, 0.01f), planeZ(0.5f, 0.01f));
  std::vector<Eigen::Vector3f> map = planeZ(0.0f, 0.01f);
  const auto patch = [&](float x0, float y0, int n, int step) {  // n x n ghosts at z = 0.5
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        map.emplace_back(x0 + 0.01f * step * i + 0.005f, y0 + 0.01f * step * j + 0.005f, 0.505f);
  };
  patch(0.1f, 0.1f, 8, 1);  // 64 points: a fragment
  patch(0.5f, 0.5f, 7, 1);  // 49 points: too small
  patch(0.1f, 0.6f, 8, 2);  // 64 points 2 cm apart: not connected
  // Diagonal neighbours (26-connectivity): a staircase of 60 points is one fragment.
  for (int i = 0; i < 60; ++i)
    map.emplace_back(0.3f + 0.01f * i + 0.005f, 0.105f + 0.01f * i, 0.505f);
  const MapMetrics m = computeMapMetrics(map, refs);
  EXPECT_EQ(m.ghost_fragments, 2u);
  EXPECT_EQ(m.ghost_fragment_points, 124u);
  std::vector<Eigen::Vector3f> sheet;  // 30 x 30 voxel centres: one group of 900
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j) sheet.emplace_back(0.01f * i + 0.005f, 0.01f * j + 0.005f, 0.0f);
  EXPECT_EQ(connectedGroups(sheet, 0.01, 50), std::vector<std::size_t>{900});
}

// A mover that stopped: the dynamic reference holds its path (z = 0.5, x < 0.5) and the place
// where it stands (z = 0.5, x >= 0.5), the settled reference only the place.
TEST(MapMetrics, SettledMoverCountsAsKeptNotAsPathGhost) {
  auto refs = makeRefs(planeZ(0.0f, 0.01f), planeZ(0.5f, 0.01f));
  for (const auto& p : planeZ(0.5f, 0.01f))
    if (p.x() >= 0.5f) refs.settled_points.push_back(p);
  refs.settled_ref = std::make_shared<PointIndex>(refs.settled_points);
  const auto patch = [](float x0, float x1) {  // the ghost plane between x0 and x1
    std::vector<Eigen::Vector3f> out;
    for (const auto& p : planeZ(0.5f, 0.01f))
      if (p.x() >= x0 && p.x() < x1) out.push_back(p);
    return out;
  };
  std::vector<Eigen::Vector3f> kept = planeZ(0.0f, 0.01f);
  for (const auto& p : patch(0.5f, 1.0f)) kept.push_back(p);
  const MapMetrics at_place = computeMapMetrics(kept, refs);
  EXPECT_NEAR(at_place.ghost_ratio, 1.0 / 3.0, 0.02);  // the shared definition counts it
  EXPECT_NEAR(at_place.path_ghost_ratio, 0.0, 1e-9);
  EXPECT_NEAR(at_place.settled_completeness, 1.0, 1e-9);

  // The first half of its path (x < 0.25, 25 cm from the place) in the map, its place not.
  std::vector<Eigen::Vector3f> path = planeZ(0.0f, 0.01f);
  const std::size_t n_static = path.size();
  for (const auto& p : patch(0.0f, 0.25f)) path.push_back(p);
  const MapMetrics on_path = computeMapMetrics(path, refs);
  EXPECT_NEAR(on_path.path_ghost_ratio, on_path.ghost_ratio, 1e-9);
  EXPECT_NEAR(on_path.path_ghost_ratio, 1.0 - static_cast<double>(n_static) / path.size(), 0.01);
  EXPECT_NEAR(on_path.settled_completeness, 0.0, 1e-9);

  // Without a settled reference both stay 0.
  const MapMetrics plain =
      computeMapMetrics(path, makeRefs(planeZ(0.0f, 0.01f), planeZ(0.5f, 0.01f)));
  EXPECT_EQ(plain.path_ghost_ratio, 0.0);
  EXPECT_EQ(plain.settled_completeness, 0.0);
}

TEST(PlyIo, ReadsAsciiAndBinaryWithExtraProperties) {
  const auto dir = freshTempDir("ply_io");
  const std::string ascii = (dir / "a.ply").string();
  std::ofstream(ascii) << "ply\nformat ascii 1.0\nelement vertex 2\nproperty float nx\n"
                          "property float x\nproperty float y\nproperty float z\n"
                          "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                          "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                          "0 1 2 3 10 20 30\n0 4 5 6 40 50 60\n3 0 1 1\n";
  const PlyData a = readPly(ascii, true);
  ASSERT_EQ(a.vertices.size(), 2u);
  EXPECT_TRUE(a.vertices[1].isApprox(Eigen::Vector3f(4, 5, 6)));
  EXPECT_EQ(a.colors[1][2], 60);
  EXPECT_EQ(a.triangles.size(), 1u);

  PlyData b;
  b.vertices = {{1, 2, 3}, {-1, 0.5f, 2}, {0, 0, 0}};
  b.colors = {{1, 2, 3}, {4, 5, 6}, {7, 8, 9}};
  b.triangles = {{0, 1, 2}};
  const std::string bin = (dir / "b.ply").string();
  writeAtomically(bin, [&](const std::string& tmp) { writePly(tmp, b); });
  const PlyData c = readPly(bin, true);
  ASSERT_EQ(c.vertices.size(), 3u);
  EXPECT_TRUE(c.vertices[1].isApprox(b.vertices[1]));
  EXPECT_EQ(c.colors[2][0], 7);
  ASSERT_EQ(c.triangles.size(), 1u);
  EXPECT_EQ(c.triangles[0][2], 2u);
  EXPECT_EQ(readPlyVertices(bin).size(), 3u);
  try {
    readPlyVertices((dir / "missing.ply").string());
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.ply"), std::string::npos);
  }
}

// Real data (every 40th frame of teddy_dyn_dev, ground-truth poses): the static-point extraction
// with the ground-truth masks keeps ghosts out, the unmasked cloud is full of them, and the
// README's "masked" row (people pixels 255 and 128 removed) is reproduced.
TEST(MapMetricsRealData, MaskedVersusNaiveOnTeddyDynDev) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  const std::string dir = (sharedData() / "dynamic" / "teddy_dyn_dev").string();
  const TumSequence seq = TumSequence::open(dir, DatasetOptions{});
  const auto gt = readTrajectory(dir + "/groundtruth.txt");
  const ReferenceClouds refs = loadReferenceClouds(dir);
  const PinholeCamera cam = cameraPreset("freiburg3");
  StaticPointsOptions raw;
  raw.depth_min_m = 0.0;
  raw.mask_dilation_px = 0;
  raw.depth_edge_threshold_m = 0.0;
  std::vector<Eigen::Vector3f> naive, masked, readme_masked;
  for (std::size_t i = 10; i < seq.size(); i += 40) {
    const auto& e = seq.entries()[i];
    auto it = std::lower_bound(gt.begin(), gt.end(), e.rgb_timestamp_s,
                               [](const TimedPose& p, double t) { return p.timestamp_s < t; });
    ASSERT_NE(it, gt.end());
    const Eigen::Isometry3f T = it->T_W_C.cast<float>();  // 100 Hz: nearest within 10 ms
    if (e.depth_path.empty()) continue;                   // colour frame without associated depth
    const FrameLoad load = seq.load(i);
    ASSERT_TRUE(load.ok) << load.error;
    const std::string mask_path =
        dir + "/mask/" + std::filesystem::path(e.rgb_path).stem().string() + ".png";
    const cv::Mat mask = cv::imread(mask_path, cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(mask.empty()) << mask_path;
    const cv::Mat people = (mask > 0) / 255 * 255;
    auto add = [&](const cv::Mat& m, const StaticPointsOptions& o,
                   std::vector<Eigen::Vector3f>* out) {
      for (const auto& p :
           extractStaticPoints(cam, load.frame.bgr, load.frame.depth_m, m, o).points_C)
        out->push_back(T * p);
    };
    add(cv::Mat(), raw, &naive);
    add(mask, StaticPointsOptions{}, &masked);
    add(people, raw, &readme_masked);
  }
  MapMetricsOptions fast;
  fast.completeness = false;  // keeps the test short; both are covered above
  fast.exact_far_distances = false;
  const MapMetrics n = computeMapMetrics(naive, refs, Eigen::Isometry3d::Identity(), fast);
  const MapMetrics m = computeMapMetrics(masked, refs, Eigen::Isometry3d::Identity(), fast);
  const MapMetrics r = computeMapMetrics(readme_masked, refs, Eigen::Isometry3d::Identity(), fast);
  EXPECT_GT(n.ghost_ratio, 0.15);
  EXPECT_LT(n.precision, 0.8);
  EXPECT_LE(m.ghost_ratio, 0.005);
  EXPECT_GT(m.precision, 0.8);  // the standing person (mask 128) stays and lowers precision
  EXPECT_GE(r.precision, 0.99);
  EXPECT_LE(r.ghost_ratio, 0.002);
  EXPECT_LT(r.accuracy_mean_m, 0.02);
}

}  // namespace
}  // namespace dynamap::test
