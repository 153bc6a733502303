#pragma once

#include <cmath>
#include <cstdint>

#include <Eigen/Core>

#include "dynamap/mapping/voxel_key.hpp"

namespace dynamap::plugin {

/// The key of the voxel holding p (dynamap::packVoxelKey of its integer cell).
inline std::uint64_t voxelKey(const Eigen::Vector3f& p, float inv_voxel) {
  return packVoxelKey(static_cast<std::int64_t>(std::floor(p.x() * inv_voxel)),
                      static_cast<std::int64_t>(std::floor(p.y() * inv_voxel)),
                      static_cast<std::int64_t>(std::floor(p.z() * inv_voxel)));
}

/// Running centroid and colour of the points in one voxel.
struct VoxelAccum {
  Eigen::Vector3f sum = Eigen::Vector3f::Zero();
  std::uint32_t rgb_sum[3] = {0, 0, 0};
  std::uint32_t count = 0;
  void add(const Eigen::Vector3f& p, const std::uint8_t* rgb, std::uint32_t n = 1) {
    sum += p * static_cast<float>(n);
    for (int k = 0; k < 3; ++k) rgb_sum[k] += rgb[k] * n;
    count += n;
  }
};

}  // namespace dynamap::plugin
