#pragma once

#include <cmath>
#include <cstdint>

#include <Eigen/Core>

namespace dynamap::plugin {

/// Packs the integer voxel coordinates of p (21 bits per axis, +-10 km at 1 cm) into 64 bits.
inline std::uint64_t voxelKey(const Eigen::Vector3f& p, float inv_voxel) {
  constexpr std::int64_t kOffset = 1 << 20;
  constexpr std::uint64_t kMask = (1u << 21) - 1;
  const auto x = static_cast<std::uint64_t>(std::int64_t(std::floor(p.x() * inv_voxel)) + kOffset);
  const auto y = static_cast<std::uint64_t>(std::int64_t(std::floor(p.y() * inv_voxel)) + kOffset);
  const auto z = static_cast<std::uint64_t>(std::int64_t(std::floor(p.z() * inv_voxel)) + kOffset);
  return (x & kMask) | ((y & kMask) << 21) | ((z & kMask) << 42);
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
