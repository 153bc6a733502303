#include "tsdf_volume.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include "dynamap/core/rounding.hpp"
#include "dynamap/mapping/radix_sort.hpp"

namespace dynamap::plugin {
namespace {

constexpr int kLeafDim = 8;  // openvdb::FloatTree::LeafNodeType::DIM

using Key = std::uint64_t;
Key packLeaf(const openvdb::Coord& c) {
  constexpr std::int64_t kOffset = 1 << 20;
  constexpr std::uint64_t kMask = (1u << 21) - 1;
  return (std::uint64_t(c.x() / kLeafDim + kOffset) & kMask) |
         ((std::uint64_t(c.y() / kLeafDim + kOffset) & kMask) << 21) |
         ((std::uint64_t(c.z() / kLeafDim + kOffset) & kMask) << 42);
}
openvdb::Coord unpackLeaf(Key k) {
  constexpr std::int64_t kOffset = 1 << 20;
  constexpr std::uint64_t kMask = (1u << 21) - 1;
  return openvdb::Coord(int((std::int64_t(k & kMask) - kOffset) * kLeafDim),
                        int((std::int64_t((k >> 21) & kMask) - kOffset) * kLeafDim),
                        int((std::int64_t((k >> 42) & kMask) - kOffset) * kLeafDim));
}
// Origin of the leaf holding world point p.
openvdb::Coord leafOf(const Eigen::Vector3d& p_W, double inv_voxel) {
  const auto idx = [&](double v) {
    const int i = static_cast<int>(roundHalfAway(v * inv_voxel));
    return i & ~(kLeafDim - 1);
  };
  return openvdb::Coord(idx(p_W.x()), idx(p_W.y()), idx(p_W.z()));
}

using FloatLeaf = openvdb::FloatTree::LeafNodeType;
using ColorLeaf = openvdb::Vec3STree::LeafNodeType;

/// Per block, its leaf in each grid (free: empty without free votes).
struct GridLeaves {
  std::vector<FloatLeaf*> tsdf, weight, free;
  std::vector<ColorLeaf*> color;
};

/// The leaves of `blocks` in each grid, created where missing (`free` null: not used). Each
/// grid's tree is touched by one thread (trees are not safe for concurrent writes).
GridLeaves touchLeaves(const std::vector<openvdb::Coord>& blocks, openvdb::FloatGrid& tsdf,
                       openvdb::FloatGrid& weight, openvdb::Vec3SGrid& color,
                       openvdb::FloatGrid* free) {
  GridLeaves leaves;
  leaves.tsdf.resize(blocks.size());
  leaves.weight.resize(blocks.size());
  leaves.color.resize(blocks.size());
  leaves.free.resize(free != nullptr ? blocks.size() : 0);
  auto touch = [&blocks](auto& grid, auto& out) {
    auto acc = grid.getAccessor();
    for (std::size_t i = 0; i < blocks.size(); ++i) out[i] = acc.touchLeaf(blocks[i]);
  };
  tbb::parallel_invoke([&] { touch(tsdf, leaves.tsdf); }, [&] { touch(weight, leaves.weight); },
                       [&] { touch(color, leaves.color); },
                       [&] {
                         if (free != nullptr) touch(*free, leaves.free);
                       });
  return leaves;
}

/// One block's leaves (free: null without free votes).
struct BlockLeaves {
  FloatLeaf& tsdf;
  FloatLeaf& weight;
  ColorLeaf& color;
  FloatLeaf* free;
};

/// Voxel (index coordinates) -> camera point -> depth-image pixel, in float.
struct VoxelProjector {
  Eigen::Matrix3f R;       ///< of T_C_W
  Eigen::Vector3f t;       ///< of T_C_W
  Eigen::Vector3f step_z;  ///< one voxel along the world z axis, in the camera
  float vs, trunc, fx, fy, cx, cy, cols, rows;
};

VoxelProjector makeProjector(const PinholeCamera& camera, const Eigen::Isometry3d& T_W_C,
                             const TsdfOptions& options, const cv::Size& image) {
  const Eigen::Isometry3d T_C_W = T_W_C.inverse();
  VoxelProjector p;
  p.R = T_C_W.rotation().cast<float>();
  p.t = T_C_W.translation().cast<float>();
  p.vs = static_cast<float>(options.voxel_size_m);
  p.trunc = static_cast<float>(options.truncation_m);
  p.fx = static_cast<float>(camera.fx), p.fy = static_cast<float>(camera.fy);
  p.cx = static_cast<float>(camera.cx), p.cy = static_cast<float>(camera.cy);
  p.step_z = p.R.col(2) * p.vs;
  p.cols = static_cast<float>(image.width), p.rows = static_cast<float>(image.height);
  return p;
}

/// Fuses one observation, signed distance `sdf` (within -trunc..), into voxel n of the block;
/// `colour`: the pixel's, or null.
void updateVoxel(const BlockLeaves& leaves, openvdb::Index n, float sdf, float trunc,
                 const cv::Vec3b* colour, const TsdfOptions& options) {
  FloatLeaf* fl = leaves.free;
  if (fl != nullptr && sdf > trunc) {
    fl->setValueOn(n, fl->getValue(n) + 1.0f);
    return;
  }
  const float w_old = leaves.weight.getValue(n);
  const float obs = std::min(1.0f, sdf / trunc);
  float w = 1.0f;
  if (options.linear_weighting && sdf < 0.0f) w = std::max(0.05f, 1.0f + sdf / trunc);
  const float w_sum = w_old + w;
  const float w_new = std::min(w_sum, options.max_weight);
  leaves.tsdf.setValueOn(n, (leaves.tsdf.getValue(n) * w_old + obs * w) / w_sum);
  leaves.weight.setValueOn(n, w_new);
  if (fl != nullptr && w_sum > w_new) {
    // The weight stopped at max_weight; the vote still counts this view (see votedTsdf).
    fl->setValueOn(n, fl->getValue(n) - options.free_vote_ratio * (w_sum - w_new));
  }
  if (colour != nullptr && std::fabs(sdf) < trunc) {
    const cv::Vec3b& p = *colour;
    const openvdb::Vec3s c_new(p[2], p[1], p[0]);
    leaves.color.setValueOn(n, (leaves.color.getValue(n) * w_old + c_new * w) / (w_old + w));
  }
}

/// The 8 voxels of the block's column (x, y) projected into the depth image and fused.
void integrateColumn(const BlockLeaves& leaves, const openvdb::Coord& o, int x, int y,
                     const VoxelProjector& p, const cv::Mat& depth_m, const cv::Mat& bgr,
                     bool has_colour, const TsdfOptions& options) {
  // The column's 8 voxels: their camera points one step apart (summed in order), then their
  // projections side by side (no branch: the compiler does 4 at a time), then the checks and
  // updates one by one.
  std::array<float, kLeafDim> px, py, pz, uf, vf;
  Eigen::Vector3f p_C = p.R * (Eigen::Vector3f(o.x() + x, o.y() + y, o.z()) * p.vs) + p.t;
  for (int z = 0; z < kLeafDim; ++z, p_C += p.step_z) {
    px[z] = p_C.x();
    py[z] = p_C.y();
    pz[z] = p_C.z();
  }
  for (int z = 0; z < kLeafDim; ++z) {
    const float inv_z = 1.0f / pz[z];
    uf[z] = p.fx * px[z] * inv_z + p.cx + 0.5f;
    vf[z] = p.fy * py[z] * inv_z + p.cy + 0.5f;
  }
  for (int z = 0; z < kLeafDim; ++z) {
    if (pz[z] <= 0.05f) continue;
    // static_cast<int> truncates: the pixel is inside iff -1 < uf < cols (NaN is not).
    if (!(uf[z] > -1.0f && vf[z] > -1.0f && uf[z] < p.cols && vf[z] < p.rows)) continue;
    const int u = static_cast<int>(uf[z]), v = static_cast<int>(vf[z]);
    const float d = depth_m.at<float>(v, u);
    if (!(d > 0.0f)) continue;
    const float sdf = d - pz[z];
    if (sdf < -p.trunc) continue;
    const openvdb::Index n = (x << 6) | (y << 3) | z;
    updateVoxel(leaves, n, sdf, p.trunc, has_colour ? &bgr.at<cv::Vec3b>(v, u) : nullptr, options);
  }
}

}  // namespace

TsdfVolume::TsdfVolume(const TsdfOptions& options) : options_(options) {
  openvdb::initialize();  // idempotent, registers grid types for I/O
  reset();
}

void TsdfVolume::reset() {
  if (loaded_.tsdf) {
    tsdf_ = loaded_.tsdf->deepCopy();
    weight_ = loaded_.weight->deepCopy();
    color_ = loaded_.color->deepCopy();
    free_ = loaded_.free->deepCopy();
    return;
  }
  const auto transform = openvdb::math::Transform::createLinearTransform(options_.voxel_size_m);
  tsdf_ = openvdb::FloatGrid::create(1.0f);
  tsdf_->setTransform(transform);
  tsdf_->setName("tsdf");
  tsdf_->setGridClass(openvdb::GRID_LEVEL_SET);
  tsdf_->insertMeta("truncation_m", openvdb::DoubleMetadata(options_.truncation_m));
  weight_ = openvdb::FloatGrid::create(0.0f);
  weight_->setTransform(transform->copy());
  weight_->setName("weight");
  color_ = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
  color_->setTransform(transform->copy());
  color_->setName("color");
  free_ = openvdb::FloatGrid::create(0.0f);
  free_->setTransform(transform->copy());
  free_->setName("free_views");
}

void TsdfVolume::importVdb(const std::string& path) {
  loaded_ = readVdb(path);
  reset();
}

// free_ holds, per voxel, the views that saw through it minus free_vote_ratio x the band weight
// that max_weight cut off, so `free > ratio x weight` is `see-throughs > ratio x every band view`.
openvdb::FloatGrid::ConstPtr TsdfVolume::votedTsdf() const {
  if (!options_.free_votes) return tsdf_;
  openvdb::FloatGrid::Ptr voted = tsdf_->deepCopy();
  auto acc = voted->getAccessor();
  auto weights = weight_->getConstAccessor();
  for (auto it = free_->cbeginValueOn(); it; ++it) {
    const float w = weights.getValue(it.getCoord());
    if (w > 0.0f && *it > options_.free_vote_ratio * w) acc.setValue(it.getCoord(), 1.0f);
  }
  return voted;
}

std::vector<openvdb::Coord> TsdfVolume::collectBlocks(const PinholeCamera& camera,
                                                      const cv::Mat& depth_m,
                                                      const Eigen::Isometry3d& T_W_C) const {
  const double inv_voxel = 1.0 / options_.voxel_size_m;
  const double trunc = options_.truncation_m;
  const double leaf_m = kLeafDim * options_.voxel_size_m;
  const int stride = std::max(1, options_.alloc_stride_px);
  const int carve = options_.space_carving ? std::max(1, options_.carve_stride_px) : 0;
  const Eigen::Vector3d origin = T_W_C.translation();
  tbb::combinable<std::vector<Key>> keys;
  tbb::parallel_for(tbb::blocked_range<int>(0, depth_m.rows), [&](const auto& range) {
    std::vector<Key>& out = keys.local();
    auto add = [&](const Eigen::Vector3d& p_W) {
      const Key k = packLeaf(leafOf(p_W, inv_voxel));
      if (out.empty() || out.back() != k) out.push_back(k);
    };
    const auto tree = tsdf_->getConstAccessor();
    for (int r = range.begin(); r < range.end(); ++r) {
      if (r % stride != 0 && (carve == 0 || r % carve != 0)) continue;
      const float* row = depth_m.ptr<float>(r);
      for (int c = 0; c < depth_m.cols; ++c) {
        const float z = row[c];
        if (!(z > 0.0f)) continue;
        const Eigen::Vector3d p_W = T_W_C * camera.backProject(c, r, z);
        const Eigen::Vector3d dir = (p_W - origin) / (p_W - origin).norm();
        if (r % stride == 0 && c % stride == 0) {
          add(p_W - trunc * dir);
          add(p_W);
          add(p_W + trunc * dir);
        }
        if (carve > 0 && r % carve == 0 && c % carve == 0) {
          // Existing blocks in front of the surface: stale surfaces get carved away.
          const double free_len = (p_W - origin).norm() - trunc;
          for (double s = 0.5 * leaf_m; s < free_len; s += 0.5 * leaf_m) {
            const openvdb::Coord leaf = leafOf(origin + s * dir, inv_voxel);
            if (tree.probeConstLeaf(leaf) != nullptr) {
              const Key k = packLeaf(leaf);
              if (out.empty() || out.back() != k) out.push_back(k);
            }
          }
        }
      }
    }
  });
  std::vector<Key> all, scratch;
  keys.combine_each([&](const std::vector<Key>& v) { all.insert(all.end(), v.begin(), v.end()); });
  radixSortByKey(all, scratch, [](Key k) { return k; });
  all.erase(std::unique(all.begin(), all.end()), all.end());
  std::vector<openvdb::Coord> blocks;
  blocks.reserve(all.size());
  for (const Key k : all) blocks.push_back(unpackLeaf(k));
  return blocks;
}

void TsdfVolume::integrate(const PinholeCamera& camera, const cv::Mat& depth_m, const cv::Mat& bgr,
                           const Eigen::Isometry3d& T_W_C) {
  const std::vector<openvdb::Coord> blocks = collectBlocks(camera, depth_m, T_W_C);
  const GridLeaves leaves =
      touchLeaves(blocks, *tsdf_, *weight_, *color_, options_.free_votes ? free_.get() : nullptr);
  const VoxelProjector projector = makeProjector(camera, T_W_C, options_, depth_m.size());
  const bool has_colour = !bgr.empty() && bgr.size() == depth_m.size();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size()), [&](const auto& range) {
    for (std::size_t b = range.begin(); b < range.end(); ++b) {
      const BlockLeaves block{*leaves.tsdf[b], *leaves.weight[b], *leaves.color[b],
                              options_.free_votes ? leaves.free[b] : nullptr};
      for (int x = 0; x < kLeafDim; ++x) {
        for (int y = 0; y < kLeafDim; ++y) {
          integrateColumn(block, blocks[b], x, y, projector, depth_m, bgr, has_colour, options_);
        }
      }
    }
  });
}

std::size_t TsdfVolume::memoryBytes() const {
  std::size_t bytes =
      tsdf_->memUsage() + weight_->memUsage() + color_->memUsage() + free_->memUsage();
  if (loaded_.tsdf) {  // kept for reset()
    bytes += loaded_.tsdf->memUsage() + loaded_.weight->memUsage() + loaded_.color->memUsage() +
             loaded_.free->memUsage();
  }
  return bytes;
}

}  // namespace dynamap::plugin
