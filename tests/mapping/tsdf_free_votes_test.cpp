// vdb_tsdf's free space as a vote (free_votes): a floor just past a table's edge, seen by views
// whose poses are off by a degree or two, keeps its surface; a thing that only the first views
// saw and the later ones see through is carved whole; one that most views saw stays.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

#include "dynamap/mapping/ply_io.hpp"
#include "mapping_test_utils.hpp"

namespace dynamap::test {
namespace {

namespace fs = std::filesystem;

PinholeCamera halfVga() {
  PinholeCamera c;
  c.width = 320;
  c.height = 240;
  c.fx = c.fy = 270.0;
  c.cx = 159.5;
  c.cy = 119.5;
  return c;
}

/// Camera k of n 1.3 m above the floor z = 0, on an arc of 3 m radius around the origin,
/// looking at it.
Eigen::Isometry3d floorPose(int k, int n) {
  const double s = n > 1 ? static_cast<double>(k) / (n - 1) : 0.0;
  const double a = -M_PI / 2 - 1.0 + 2.0 * s;
  const Eigen::Vector3d eye(3.0 * std::cos(a), 3.0 * std::sin(a), 1.3);
  const Eigen::Vector3d target(0.0, 0.0, 0.0);
  const Eigen::Vector3d z = (target - eye).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = z.cross(x);
  T.linear().col(2) = z;
  T.translation() = eye;
  return T;
}

/// Depth of the floor (and of `box` if given) with Kinect-like noise and disparity steps.
cv::Mat noisyDepth(const PinholeCamera& cam, const Eigen::Isometry3d& T_W_C, std::mt19937& rng,
                   const Box* box = nullptr) {
  cv::Mat depth = cv::Mat::zeros(cam.height, cam.width, CV_32FC1);
  std::normal_distribution<double> unit(0.0, 1.0);
  const Eigen::Vector3d o = T_W_C.translation();
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const Eigen::Vector3d d =
          T_W_C.linear() * Eigen::Vector3d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
      double t = d.z() < -1e-6 ? -o.z() / d.z() : std::numeric_limits<double>::infinity();
      if (box != nullptr) t = std::min(t, box->intersect(o, d));
      if (!(t < 4.5)) continue;  // t is the depth: d has a unit z in the camera
      const double sigma = 0.0012 + 0.0019 * (t - 0.4) * (t - 0.4);
      const double noisy = t + sigma * unit(rng);
      const double step = 2.85e-3;  // disparity quantisation, in 1/m
      depth.at<float>(v, u) = static_cast<float>(1.0 / (std::round(1.0 / noisy / step) * step));
    }
  }
  return depth;
}

/// Integrates n views of the floor and a table (poses off by `jitter_deg` about a random axis,
/// seeded; `stale` in the first `stale_views` views only), exports, returns the mesh vertices.
std::vector<Eigen::Vector3f> floorMesh(const BackendParams& params, int n, double jitter_deg,
                                       const std::string& name, const Box* stale = nullptr,
                                       int stale_views = 1, unsigned seed = 7) {
  const auto registry = BackendRegistry::scan({pluginDir()});
  auto backend = registry.create("vdb_tsdf", params);
  const PinholeCamera cam = halfVga();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> axis(-1.0, 1.0);
  const cv::Mat bgr(cam.height, cam.width, CV_8UC3, cv::Scalar(90, 120, 150));
  for (int k = 0; k < n; ++k) {
    const Eigen::Isometry3d T = floorPose(k, n);
    const Box table{{-0.3, -0.3, 0.0}, {0.3, 0.3, 0.6}};
    const cv::Mat depth =
        noisyDepth(cam, T, rng, k < stale_views && stale != nullptr ? stale : &table);
    Eigen::Vector3d a;
    for (int i = 0; i < 3; ++i) a[i] = axis(rng);  // in this order (arguments have none)
    Eigen::Isometry3d T_given = T;
    T_given.linear() =
        T.linear() * Eigen::AngleAxisd(jitter_deg * M_PI / 180.0, a.normalized()).matrix();
    KeyframeView view;
    view.id = static_cast<std::uint64_t>(k);
    view.timestamp_s = 0.1 * k;
    view.T_W_C = T_given;
    view.camera = &cam;
    view.bgr = &bgr;
    view.static_depth_m = &depth;
    backend->integrate(view);
  }
  const fs::path dir = freshTempDir("tsdf_votes_" + name);
  backend->exportMap(dir.string());
  return readPly((dir / "mesh.ply").string()).vertices;
}

/// Share of a 5 cm grid over the floor within 0.5 m of the origin that has a mesh vertex within 5
/// cm. The vertices near the floor are bucketed into 5 cm cells; a grid point looks at the 3 x 3
/// cells around its own (a brute-force search over every vertex took 2 of the 12 s, and most of
/// the 155 s under ASan + UBSan with coverage instrumentation).
double floorCoverage(const std::vector<Eigen::Vector3f>& mesh) {
  constexpr float kReach = 0.05f;
  const auto cell = [](double v) { return static_cast<int>(std::floor(v / kReach)); };
  std::map<std::pair<int, int>, std::vector<Eigen::Vector3f>> near_floor;
  for (const auto& p : mesh) {
    if (std::fabs(p.z()) < kReach) near_floor[{cell(p.x()), cell(p.y())}].push_back(p);
  }
  int covered = 0, all = 0;
  for (double y = -1.0; y <= 1.0; y += 0.05) {
    for (double x = -1.0; x <= 1.0; x += 0.05) {
      if (std::max(std::fabs(x), std::fabs(y)) < 0.4) continue;
      ++all;
      const Eigen::Vector3f q(static_cast<float>(x), static_cast<float>(y), 0.0f);
      bool hit = false;
      for (int dy = -1; dy <= 1 && !hit; ++dy) {
        for (int dx = -1; dx <= 1 && !hit; ++dx) {
          const auto it = near_floor.find({cell(x) + dx, cell(y) + dy});
          if (it == near_floor.end()) continue;
          for (const auto& p : it->second) hit = hit || (p - q).squaredNorm() < kReach * kReach;
        }
      }
      covered += hit ? 1 : 0;
    }
  }
  return static_cast<double>(covered) / all;
}

bool vdbBuilt() { return !BackendRegistry::scan({pluginDir()}).pluginPath("vdb_tsdf").empty(); }

const BackendParams kDefaults = {{"voxel_size_m", "0.02"}};
const BackendParams kAveraged = {{"voxel_size_m", "0.02"}, {"free_votes", "false"}};

// The floor behind the table: views whose poses are 1.5 deg off (random axes, 6 seeded draws) see
// it past the table's edge where their ray ends farther away. Averaged into the distances that
// free space eats the floor (measured: 0.824 of it left over the draws, worst 0.635); voted 0.886
// (worst 0.688; 0.922 / 0.790 at free_vote_ratio 1). Exact poses: 0.99.
TEST(TsdfFreeVotes, FloorBehindAnEdgeSurvivesPoseErrors) {
  if (!vdbBuilt()) GTEST_SKIP() << "vdb_tsdf backend not built";
  EXPECT_GE(floorCoverage(floorMesh(kDefaults, 10, 0.0, "exact")), 0.97);
  double voted = 0.0, averaged = 0.0;
  for (unsigned seed = 1; seed <= 6; ++seed) {
    voted += floorCoverage(floorMesh(kDefaults, 10, 1.5, "voted", nullptr, 1, seed)) / 6;
    averaged += floorCoverage(floorMesh(kAveraged, 10, 1.5, "averaged", nullptr, 1, seed)) / 6;
  }
  EXPECT_GE(voted, 0.85);
  EXPECT_LE(averaged, voted - 0.03) << "the scene no longer shows what the votes are for";
}

// The bag of the tests below, on the floor.
const Box kBag{{-1.35, -0.95, 0.0}, {-1.05, -0.65, 0.6}};

// Mesh vertices inside (2 cm around) `box` higher than z above the floor.
std::size_t above(const std::vector<Eigen::Vector3f>& mesh, const Box& box, float z) {
  std::size_t n = 0;
  for (const auto& p : mesh) n += p.z() > z && box.contains(p.cast<double>(), 0.02) ? 1 : 0;
  return n;
}

// A bag 1-2 m in front of the floor the views see behind it, there in the first views only (taken
// away, unmasked): carved down to the floor when one or two views saw it, kept when most saw it
// (measured: there in the first 3 of 10 views, 20 vertices stay voted, 128 averaged; 736 at
// free_vote_ratio 1, as only some later views see through it).
TEST(TsdfFreeVotes, ThingMostViewsSawThroughIsCarved) {
  if (!vdbBuilt()) GTEST_SKIP() << "vdb_tsdf backend not built";
  EXPECT_EQ(above(floorMesh(kDefaults, 10, 0.0, "bag1", &kBag, 1), kBag, 0.05f), 0u);
  EXPECT_LE(above(floorMesh(kDefaults, 10, 0.0, "bag2", &kBag, 2), kBag, 0.05f), 50u);
  const std::size_t whole = above(floorMesh(kDefaults, 10, 0.0, "bag10", &kBag, 10), kBag, 0.15f);
  EXPECT_GT(whole, 500u);
  EXPECT_GT(above(floorMesh(kDefaults, 10, 0.0, "bag8", &kBag, 8), kBag, 0.15f), whole / 2);
  const BackendParams no_carving = {{"voxel_size_m", "0.02"}, {"space_carving", "false"}};
  EXPECT_GT(above(floorMesh(no_carving, 10, 0.0, "bag_kept", &kBag, 1), kBag, 0.15f), 100u)
      << "the first view did not put the bag into the volume";
}

// The vote counts every view that saw a voxel in the band, also past max_weight (where the
// distance's weight stops growing): a long sequence's wall that many views saw is not carved by
// fewer see-throughs than ratio x those views. max_weight 2 stands in for 100 in a 10-view scene:
// the bag there in the first 4 / 6 of 10 views keeps as much of itself as with the weight uncapped
// (measured: 652 / 1688 vertices vs 636 / 1677; against the capped weight, as before, 361 / 1098).
TEST(TsdfFreeVotes, BandViewsPastMaxWeightStillCount) {
  if (!vdbBuilt()) GTEST_SKIP() << "vdb_tsdf backend not built";
  const BackendParams capped = {{"voxel_size_m", "0.02"}, {"max_weight", "2"}};
  const double whole = above(floorMesh(kDefaults, 10, 0.0, "cap_whole", &kBag, 10), kBag, 0.15f);
  ASSERT_GT(whole, 500.0);
  for (const int views : {4, 6}) {
    const std::string name = "cap" + std::to_string(views);
    const double n_capped = above(floorMesh(capped, 10, 0.0, name, &kBag, views), kBag, 0.15f);
    const double n_free =
        above(floorMesh(kDefaults, 10, 0.0, name + "u", &kBag, views), kBag, 0.15f);
    EXPECT_NEAR(n_capped, n_free, 0.05 * whole) << "bag in the first " << views << " views";
  }
}

}  // namespace
}  // namespace dynamap::test
