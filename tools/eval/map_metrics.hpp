#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace dynamap {

/// Nearest-neighbour index over a fixed point set (a small k-d tree; no PCL). Thread-safe queries.
class PointIndex {
 public:
  explicit PointIndex(std::vector<Eigen::Vector3f> points);
  /// Distance to the nearest point; infinity when there is none within max_distance.
  float nearestDistance(const Eigen::Vector3f& q,
                        float max_distance = std::numeric_limits<float>::infinity()) const;
  std::size_t size() const { return points_.size(); }

 private:
  struct Node {
    int axis = -1;                     ///< -1 = leaf (else the axis its points were split along)
    std::uint32_t begin = 0, end = 0;  ///< leaf range
    std::uint32_t left = 0, right = 0;
    Eigen::Vector3f lo, hi;  ///< bounding box of its points
  };
  std::uint32_t build(std::uint32_t begin, std::uint32_t end);
  void search(std::uint32_t node, const Eigen::Vector3f& q, float* best_sq) const;
  std::vector<Eigen::Vector3f> points_;
  std::vector<Node> nodes_;
};

/// The references of the dynamic sequences (shared/data/dynamic/README.md), kd-indexed.
struct ReferenceClouds {
  std::shared_ptr<const PointIndex> static_ref;   ///< reference_static.ply
  std::shared_ptr<const PointIndex> dynamic_ref;  ///< reference_dynamic.ply (may be null)
  /// The static reference reduced to kCoarseVoxelM centroids: bounds far queries (optional).
  std::shared_ptr<const PointIndex> static_coarse;
  static constexpr double kCoarseVoxelM = 0.05;
  std::vector<Eigen::Vector3f> static_points;  ///< for completeness
  /// reference_settled.ply (tests/movers/make_movers.py; may be empty): where a mover stands
  /// after it stopped. It belongs in the map, though reference_dynamic.ply holds that place too.
  std::vector<Eigen::Vector3f> settled_points;
  std::shared_ptr<const PointIndex> settled_ref;
};
/// Reads <dir>/reference_static.ply, and reference_dynamic.ply and reference_settled.ply if
/// present.
ReferenceClouds loadReferenceClouds(const std::string& dir);

struct MapMetrics {
  std::size_t map_points = 0;  ///< after the 1 cm voxel reduction
  double accuracy_mean_m = 0.0;
  double precision = 0.0;
  double completeness = 0.0;
  double fscore = 0.0;
  double ghost_ratio = 0.0;
  /// Connected groups (26-connectivity on the voxel_m grid) of at least
  /// MapMetricsOptions::ghost_fragment_min_points ghost points, and the points in them.
  std::size_t ghost_fragments = 0;
  std::size_t ghost_fragment_points = 0;
  /// With a settled reference (else 0): the ghosts farther than ghost_dynamic_m from it (where
  /// movers only passed), and the share of its points with a map point within threshold_m (the
  /// stopped mover kept where it stands).
  double path_ghost_ratio = 0.0;
  double settled_completeness = 0.0;
};

struct MapMetricsOptions {
  double voxel_m = 0.01;               ///< map reduced to one centroid per voxel
  double threshold_m = 0.05;           ///< precision / completeness / ghost static distance
  double ghost_dynamic_m = 0.03;       ///< ghost: within this of the dynamic reference
  int ghost_fragment_min_points = 50;  ///< smaller connected groups of ghosts are not fragments
  bool completeness = true;            ///< false skips the (reference -> map) queries
  /// false: distances beyond threshold_m come from the 5 cm coarse reference (accuracy off by
  /// < 9 cm for those points; precision, completeness and ghost ratio stay exact). Much faster
  /// for maps full of far-off ghosts.
  bool exact_far_distances = true;
};

/// README "Metrics": moves the map by T_ref_map, reduces it to 1 cm voxel centroids, then
/// accuracy (mean NN distance to the static reference), precision, completeness, F-score and
/// ghost ratio (within 3 cm of the dynamic reference and more than 5 cm from the static one).
MapMetrics computeMapMetrics(const std::vector<Eigen::Vector3f>& map_points_W,
                             const ReferenceClouds& refs,
                             const Eigen::Isometry3d& T_ref_map = Eigen::Isometry3d::Identity(),
                             const MapMetricsOptions& options = {});

/// Connected groups of the given points on their voxel_m grid (26-connectivity; points in the
/// same voxel are one cell): the sizes (in points) of the groups of at least min_points.
std::vector<std::size_t> connectedGroups(const std::vector<Eigen::Vector3f>& points, double voxel_m,
                                         std::size_t min_points);

/// One centroid per voxel of size voxel_m.
std::vector<Eigen::Vector3f> voxelCentroids(const std::vector<Eigen::Vector3f>& points,
                                            double voxel_m);

/// Vertices of a PLY file (point cloud or mesh; ASCII or binary_little_endian; extra properties
/// ignored). Throws std::runtime_error naming the file.
std::vector<Eigen::Vector3f> readPlyVertices(const std::string& path);

}  // namespace dynamap
