#pragma once

// One keyframe's points reduced to voxel centroids, kept in its camera frame so the map can
// follow later pose corrections: 20 bytes a voxel (float centroid, mean colour, point count)
// instead of 28 for float sums; in RAM while the keyframe is active, then in a spill file.
// (int16 centroids on a 1/16-voxel grid, 12 bytes, moved ~2 % of re-placed centroids into a
// neighbouring voxel: a reloaded map lost 2.4 % of its voxels.)

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "voxel_key.hpp"
#include "voxel_spill_file.hpp"

namespace dynamap::plugin {

struct CompactVoxel {
  std::array<float, 3> p;  ///< centroid in the camera frame, metres
  std::array<std::uint8_t, 3> rgb;
  std::uint8_t unused = 0;
  std::uint16_t count = 0;  ///< points, saturated at 65535
};
static_assert(sizeof(CompactVoxel) == 20, "20 bytes a voxel");

class KeyframeVoxels {
 public:
  explicit KeyframeVoxels(const std::vector<VoxelAccum>& voxels_C) {
    voxels_.reserve(voxels_C.size());
    for (const VoxelAccum& a : voxels_C) voxels_.push_back(compact(a));
  }

  /// Calls f(centroid_C, rgb, count) for each voxel; `buffer` holds them if spilled.
  template <typename F>
  void forEach(std::vector<CompactVoxel>& buffer, F&& f) const {
    const std::vector<CompactVoxel>* voxels = &voxels_;
    if (spill_) {
      spill_->read(span_, buffer);
      voxels = &buffer;
    }
    for (const CompactVoxel& v : *voxels) {
      f(Eigen::Vector3f(v.p[0], v.p[1], v.p[2]), v.rgb.data(), static_cast<std::uint32_t>(v.count));
    }
  }

  /// Moves the voxels out of RAM into `file` (which must outlive this).
  void spill(SpillFile<CompactVoxel>& file) {
    if (spill_) return;
    span_ = file.append(voxels_);
    spill_ = &file;
    std::vector<CompactVoxel>().swap(voxels_);
  }

  std::size_t size() const { return spill_ ? span_.count : voxels_.size(); }
  /// Bytes held in RAM.
  std::size_t bytes() const { return voxels_.capacity() * sizeof(CompactVoxel); }

 private:
  static CompactVoxel compact(const VoxelAccum& a) {
    CompactVoxel v;
    const Eigen::Vector3f c = a.sum / static_cast<float>(a.count);
    for (int k = 0; k < 3; ++k) {
      v.p[k] = c[k];
      v.rgb[k] = static_cast<std::uint8_t>((a.rgb_sum[k] + a.count / 2) / a.count);
    }
    v.count = static_cast<std::uint16_t>(std::min<std::uint32_t>(a.count, 65535));
    return v;
  }

  std::vector<CompactVoxel> voxels_;
  SpillFile<CompactVoxel>* spill_ = nullptr;
  SpillFile<CompactVoxel>::Span span_;
};

}  // namespace dynamap::plugin
