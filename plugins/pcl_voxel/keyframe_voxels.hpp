#pragma once

// One keyframe's points reduced to voxel centroids, kept compactly in its camera frame so the
// map can follow later pose corrections: 12 bytes a voxel (int16 coordinates on a per-keyframe
// grid, mean colour, point count) instead of 28 for float sums; in RAM while the keyframe is
// active, then in a spill file.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "voxel_key.hpp"
#include "voxel_spill_file.hpp"

namespace dynamap::plugin {

struct CompactVoxel {
  std::array<std::int16_t, 3> p;  ///< centroid in the camera frame, in KeyframeVoxels::unit_m
  std::array<std::uint8_t, 3> rgb;
  std::uint8_t unused = 0;
  std::uint16_t count = 0;  ///< points, saturated at 65535
};
static_assert(sizeof(CompactVoxel) == 12, "12 bytes a voxel");

class KeyframeVoxels {
 public:
  /// `grid_m`: the finest step worth keeping (a fraction of the map's voxel); coarser when the
  /// keyframe's extent does not fit int16 at that step.
  KeyframeVoxels(const std::vector<VoxelAccum>& voxels_C, float grid_m) {
    float extent = 0.0f;
    for (const VoxelAccum& a : voxels_C) {
      extent = std::max(extent, (a.sum / static_cast<float>(a.count)).cwiseAbs().maxCoeff());
    }
    unit_m_ = std::max(grid_m, extent / 32000.0f);
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
      const Eigen::Vector3f p(v.p[0] * unit_m_, v.p[1] * unit_m_, v.p[2] * unit_m_);
      f(p, v.rgb.data(), static_cast<std::uint32_t>(v.count));
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
  CompactVoxel compact(const VoxelAccum& a) const {
    CompactVoxel v;
    const Eigen::Vector3f c = a.sum / static_cast<float>(a.count);
    for (int k = 0; k < 3; ++k) {
      v.p[k] = static_cast<std::int16_t>(std::lround(c[k] / unit_m_));
      v.rgb[k] = static_cast<std::uint8_t>((a.rgb_sum[k] + a.count / 2) / a.count);
    }
    v.count = static_cast<std::uint16_t>(std::min<std::uint32_t>(a.count, 65535));
    return v;
  }

  float unit_m_ = 0.001f;
  std::vector<CompactVoxel> voxels_;
  SpillFile<CompactVoxel>* spill_ = nullptr;
  SpillFile<CompactVoxel>::Span span_;
};

}  // namespace dynamap::plugin
