#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <openvdb/openvdb.h>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "dynamap/core/camera.hpp"
#include "dynamap/mapping/ply_io.hpp"

namespace dynamap::plugin {

struct TsdfOptions {
  double voxel_size_m = 0.02;
  double truncation_m = 0.08;
  float max_weight = 100.0f;      ///< the distance's weight stops here (free votes still count)
  float min_weight = 1.0f;        ///< export: every corner of a mesh cell needs this weight
  bool space_carving = true;      ///< visit existing blocks in front of the surface
  bool linear_weighting = false;  ///< weight falls off linearly behind the surface
  int alloc_stride_px = 4;        ///< pixel step when finding the blocks around the surface
  int carve_stride_px = 12;       ///< pixel step of the rays looking for stale blocks
  /// Views that see a voxel more than the truncation in front of their surface (free space)
  /// vote instead of averaging +1 into it: the voxel is free when more views saw through it than
  /// free_vote_ratio x the views that saw it within the truncation band. Averaged, one view whose
  /// pose is a degree off past an edge erases a floor that ten views saw. 0.5: at 1 (a plain
  /// majority) a person who stood by a wall for long stays in some Bonn maps (BENCHMARKS.md).
  bool free_votes = true;
  float free_vote_ratio = 0.5f;
};

/// "crc32 <8 hex digits> bytes <n>" of the file at `path` (zlib's crc32). Written beside
/// tsdf.vdb as tsdf.vdb.crc32 and checked before OpenVDB parses the file: a length in a damaged
/// header makes OpenVDB allocate what it says (4 GB). Throws MappingError naming the file.
std::string fileDigest(const std::string& path);
inline constexpr const char* kDigestSuffix = ".crc32";

/// A colour TSDF in OpenVDB grids (tsdf normalised to [-1, 1], weight = views within the
/// truncation band, colour, and with free_votes the see-through votes), integrated
/// projectively: the 8^3 leaf blocks within the truncation band of the observed depth (and, with
/// space carving, existing blocks along the rays in front of it) are found from the depth image,
/// then every voxel of those blocks is projected into the depth image (TBB over blocks).
/// Not thread-safe.
class TsdfVolume {
 public:
  explicit TsdfVolume(const TsdfOptions& options);
  const TsdfOptions& options() const { return options_; }
  void integrate(const PinholeCamera& camera, const cv::Mat& depth_m, const cv::Mat& bgr,
                 const Eigen::Isometry3d& T_W_C);
  /// Back to the imported grids (importVdb()), or empty.
  void reset();
  /// Starts from the grids writeVdb() wrote to `path`, which reset() then comes back to. Checked
  /// first (tsdf_volume_io.cpp): the file against its digest `path`.crc32 where there is one
  /// (maps saved before it have none), grids tsdf, weight and color (free_views optional) of their
  /// types and backgrounds, this volume's voxel size and unshifted transform, its truncation_m
  /// where recorded, values finite and in range. Throws MappingError "<path>: <field>: <what>"
  /// and leaves the volume as it was.
  void importVdb(const std::string& path);
  /// tsdf with the voxels the free votes carve set to +1 (the tsdf itself without free_votes):
  /// what both exports read, made once per export.
  openvdb::FloatGrid::ConstPtr votedTsdf() const;
  /// Marching cubes (openvdb::tools::volumeToMesh) of `voted` keeping cells whose 8 corners are
  /// observed.
  PlyData extractMesh(const openvdb::FloatGrid& voted) const;
  /// The grids `voted` (named tsdf), weight, color and, with free votes, free_views.
  void writeVdb(const std::string& path, const openvdb::FloatGrid::ConstPtr& voted) const;
  std::size_t activeVoxels() const { return tsdf_->activeVoxelCount(); }
  std::size_t memoryBytes() const;

 private:
  /// The volume's grids; loaded_'s are those importVdb() read (tsdf null: none).
  struct Grids {
    openvdb::FloatGrid::Ptr tsdf, weight, free;
    openvdb::Vec3SGrid::Ptr color;
  };
  /// writeVdb()'s grids at `path`, checked against options_ (tsdf_volume_io.cpp).
  Grids readVdb(const std::string& path) const;
  std::vector<openvdb::Coord> collectBlocks(const PinholeCamera& camera, const cv::Mat& depth_m,
                                            const Eigen::Isometry3d& T_W_C) const;
  TsdfOptions options_;
  openvdb::FloatGrid::Ptr tsdf_;
  openvdb::FloatGrid::Ptr weight_;
  openvdb::Vec3SGrid::Ptr color_;
  /// free_votes: the views that saw through each voxel, less free_vote_ratio x the band weight
  /// that max_weight cut off (see votedTsdf()).
  openvdb::FloatGrid::Ptr free_;
  Grids loaded_;
};

}  // namespace dynamap::plugin
