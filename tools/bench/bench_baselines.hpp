#pragma once

#include <string>
#include <vector>

#include "bench_sequence.hpp"
#include "dynamap/mapping/static_points.hpp"

namespace dynamap::bench {

struct OctomapBaseline {
  double median_ms = 0.0;               ///< plain OcTree::insertPointCloud of the full cloud
  std::size_t plain_occupied = 0;       ///< occupied finest cells of the plain tree
  std::size_t fast_occupied = 0;        ///< occupied cells of the backend's cloud.ply
  double share_of_plain_in_fast = 0.0;  ///< |plain ∩ fast| / |plain|
};
/// Plain OctoMap on the same static points; compares with the occupied-voxel centres the
/// octomap backend exported (fast_cloud_ply).
OctomapBaseline runPlainOctomap(const std::vector<BenchFrame>& frames, const PinholeCamera& camera,
                                const StaticPointsOptions& options, double resolution_m,
                                const std::string& fast_cloud_ply);

struct VoxelGridBaseline {
  double stitch_ms = 0.0;  ///< transforming and concatenating every frame's static points
  double filter_ms = 0.0;  ///< one pcl::VoxelGrid over all of them
  std::size_t input_points = 0;
  std::size_t output_points = 0;
};
VoxelGridBaseline runOneShotVoxelGrid(const std::vector<BenchFrame>& frames,
                                      const PinholeCamera& camera,
                                      const StaticPointsOptions& options, double leaf_m);

}  // namespace dynamap::bench
