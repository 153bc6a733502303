#include "bench_baselines.hpp"

#include <chrono>

#include <octomap/OcTree.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "dynamap/core/timing.hpp"
#include "map_metrics.hpp"

namespace dynamap::bench {
namespace {

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

OctomapBaseline runPlainOctomap(const std::vector<BenchFrame>& frames, const PinholeCamera& camera,
                                const StaticPointsOptions& options, double resolution_m,
                                const std::string& fast_cloud_ply) {
  octomap::OcTree tree(resolution_m);
  std::vector<double> times;
  for (const BenchFrame& f : frames) {
    const LoadedFrame lf = readBenchFrame(f);
    const StaticPoints sp =
        extractStaticPoints(camera, lf.bgr, lf.depth_m, lf.dynamic_mask, options);
    const Eigen::Isometry3f T = f.T_W_C.cast<float>();
    octomap::Pointcloud cloud;
    cloud.reserve(sp.points_C.size());
    for (const auto& p_C : sp.points_C) {
      const Eigen::Vector3f p = T * p_C;
      cloud.push_back(p.x(), p.y(), p.z());
    }
    const Eigen::Vector3d o = f.T_W_C.translation();
    const auto t0 = std::chrono::steady_clock::now();
    tree.insertPointCloud(cloud, octomap::point3d(o.x(), o.y(), o.z()));
    times.push_back(msSince(t0));
  }
  OctomapBaseline out;
  out.median_ms = percentile(times, 50.0);
  tree.expand();
  octomap::KeySet plain;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (tree.isNodeOccupied(*it)) plain.insert(it.getKey());
  }
  out.plain_occupied = plain.size();
  std::size_t common = 0;
  const std::vector<Eigen::Vector3f> fast = readPlyVertices(fast_cloud_ply);
  out.fast_occupied = fast.size();
  for (const auto& p : fast) common += plain.count(tree.coordToKey(p.x(), p.y(), p.z()));
  out.share_of_plain_in_fast = plain.empty() ? 0.0 : static_cast<double>(common) / plain.size();
  return out;
}

VoxelGridBaseline runOneShotVoxelGrid(const std::vector<BenchFrame>& frames,
                                      const PinholeCamera& camera,
                                      const StaticPointsOptions& options, double leaf_m) {
  VoxelGridBaseline out;
  pcl::PointCloud<pcl::PointXYZ>::Ptr all(new pcl::PointCloud<pcl::PointXYZ>);
  for (const BenchFrame& f : frames) {
    const LoadedFrame lf = readBenchFrame(f);
    const StaticPoints sp =
        extractStaticPoints(camera, lf.bgr, lf.depth_m, lf.dynamic_mask, options);
    const auto t0 = std::chrono::steady_clock::now();
    const Eigen::Isometry3f T = f.T_W_C.cast<float>();
    for (const auto& p_C : sp.points_C) {
      const Eigen::Vector3f p = T * p_C;
      all->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
    }
    out.stitch_ms += msSince(t0);
  }
  out.input_points = all->size();
  const auto t0 = std::chrono::steady_clock::now();
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setInputCloud(all);
  grid.setLeafSize(static_cast<float>(leaf_m), static_cast<float>(leaf_m),
                   static_cast<float>(leaf_m));
  pcl::PointCloud<pcl::PointXYZ> filtered;
  grid.filter(filtered);
  out.filter_ms = msSince(t0);
  out.output_points = filtered.size();
  return out;
}

}  // namespace dynamap::bench
