#pragma once
// The one packing of integer voxel coordinates into a 64-bit key, shared by the visibility pass,
// the voxel backends and the map metrics. Each caller computes its cells (float or double
// products, clamping) as before; only the packing lives here.

#include <cstdint>

namespace dynamap {

constexpr int kVoxelKeyAxisBits = 21;
constexpr std::uint64_t kVoxelKeyAxisMask = (std::uint64_t{1} << kVoxelKeyAxisBits) - 1;

/// 21 bits per axis, x lowest: cell + 2^20 modulo 2^21, so cells within +-2^20 keep their own key
/// (+-10 km at 1 cm) and far ones wrap (which only merges voxels).
inline std::uint64_t packVoxelKey(std::int64_t x, std::int64_t y, std::int64_t z) {
  constexpr std::int64_t kOffset = std::int64_t{1} << (kVoxelKeyAxisBits - 1);
  const auto axis = [](std::int64_t c) {
    return static_cast<std::uint64_t>(c + kOffset) & kVoxelKeyAxisMask;
  };
  return axis(x) | (axis(y) << kVoxelKeyAxisBits) | (axis(z) << (2 * kVoxelKeyAxisBits));
}

}  // namespace dynamap
