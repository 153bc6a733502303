#pragma once
// The visibility pass's element table (mapping/src/visibility.cpp), in two parts by the parity of
// the voxel key, so that two threads fill, project and judge it side by side. Internal to
// dynamap_mapping.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "dynamap/core/camera.hpp"
#include "dynamap/mapping/flat_index.hpp"
#include "dynamap/mapping/visibility.hpp"
#include "dynamap/mapping/voxel_key.hpp"
#include "plane_fit.hpp"
#include "visibility_votes.hpp"

namespace dynamap::vis {

constexpr int kAxisBits = kVoxelKeyAxisBits;
constexpr std::uint64_t kAxisMask = kVoxelKeyAxisMask;

/// packVoxelKey of p's cell (voxels of 2 cm: +-20 km); far points wrap, which only merges voxels.
inline std::uint64_t voxelKey(const Eigen::Vector3f& p, float inv_voxel) {
  const auto cell = [inv_voxel](float v) {
    return static_cast<std::int64_t>(std::clamp(std::floor(double(v) * inv_voxel), -1e15, 1e15));
  };
  return packVoxelKey(cell(p.x()), cell(p.y()), cell(p.z()));
}

/// The key of the voxel (dx, dy, dz) cells away from `key`'s (wrapping as voxelKey() does).
inline std::uint64_t offsetKey(std::uint64_t key, int dx, int dy, int dz) {
  const int d[3] = {dx, dy, dz};
  std::uint64_t out = 0;
  for (int a = 0; a < 3; ++a) {
    const std::uint64_t cell = (key >> (kAxisBits * a)) + static_cast<std::uint64_t>(d[a]);
    out |= (cell & kAxisMask) << (kAxisBits * a);
  }
  return out;
}

/// The part of the table a voxel key belongs to: the parity of its x cell.
inline int partOf(std::uint64_t key) { return static_cast<int>(key & 1u); }

/// A keyframe's static points in runs of consecutive points of one voxel (neighbouring pixels of
/// a row mostly share a 2 cm voxel), the runs sorted by voxel key, then by their first point.
/// ordinal: the run's place in point order; starts[ordinal]: its first point.
struct VoxelRun {
  std::uint64_t key = 0;
  std::uint32_t ordinal = 0;
  std::uint32_t count = 0;
};
struct KeyedPoints {
  std::vector<VoxelRun> runs;
  std::vector<VoxelRun> scratch;  ///< for the sort
  std::vector<std::uint32_t> starts;
  std::vector<Eigen::Vector3f> points;
  std::vector<std::uint64_t> keys;  ///< one row's keys, while keying
};

/// A keyframe's runs in point order: each run's element (2 x index + part) and length. The
/// removal walks the keyframe's static pixels with them instead of keying every point again.
struct RunElements {
  std::vector<std::uint32_t> element;
  std::vector<std::uint32_t> count;
};

enum class Verdict : std::uint8_t { kKept, kRemoved, kBrief };
constexpr float kSupportRadiusM = 0.12f;  ///< onConfirmedPlane(): neighbourhood (cube half side)

/// One part of the element table: the voxels whose key has its parity.
class ElementTable {
 public:
  explicit ElementTable(int part) : part_(part) {}

  /// Adds the runs of a keyframe's keyed points that belong to this part, point by point in
  /// (voxel, point) order: one hash access per distinct voxel; sets their entries of `out`
  /// (sized by the caller; the other part sets the others). Keyframes must be added in the same
  /// order on every run (the element order and the float sums depend on it).
  void add(const KeyedPoints& in, RunElements& out) {
    const auto& runs = in.runs;
    for (std::size_t b = 0; b < runs.size();) {
      const std::uint64_t key = runs[b].key;
      if (partOf(key) != part_) {
        for (; b < runs.size() && runs[b].key == key; ++b) {
        }
        continue;
      }
      const auto [i, inserted] = index_.tryEmplace(key, static_cast<std::uint32_t>(keys_.size()));
      if (inserted) {
        elements_.emplace_back();
        keys_.push_back(key);
      }
      Element& e = elements_[i];
      for (; b < runs.size() && runs[b].key == key; ++b) {
        const std::uint32_t first = in.starts[runs[b].ordinal];
        for (std::uint32_t p = 0; p < runs[b].count; ++p) e.sum += in.points[first + p];
        e.count += runs[b].count;
        out.element[runs[b].ordinal] = 2 * i + static_cast<std::uint32_t>(part_);
        out.count[runs[b].ordinal] = runs[b].count;
      }
    }
  }

  void computeCentroids() {
    centroids_.resize(elements_.size());
    for (std::size_t i = 0; i < elements_.size(); ++i) {
      centroids_[i] = elements_[i].sum / static_cast<float>(elements_[i].count);
    }
  }

  /// Counts, for every element, whether this view (keyframe `index`) saw through it.
  void project(const PinholeCamera& camera, const VisibilityView& view,
               const Eigen::Isometry3d& T_W_C, const VisibilityOptions& options,
               std::uint32_t index) {
    const Eigen::Isometry3f T_C_W = T_W_C.inverse().cast<float>();
    const Eigen::Matrix3f R = T_C_W.linear();
    const Eigen::Vector3f t = T_C_W.translation();
    const float s = 1.0f / static_cast<float>(view.downsample);
    const auto fx = static_cast<float>(camera.fx) * s, fy = static_cast<float>(camera.fy) * s;
    const auto cx = static_cast<float>(camera.cx) * s, cy = static_cast<float>(camera.cy) * s;
    const auto margin = static_cast<float>(options.margin_m);
    const auto per_m2 = static_cast<float>(options.margin_per_m2);
    const auto cap = static_cast<std::uint32_t>(std::max(1, options.min_views));
    const int w = view.near_m.cols, h = view.near_m.rows;
    const bool has_mask = view.moving.size() == view.near_m.size();
    for (std::size_t i = 0; i < elements_.size(); ++i) {
      const Eigen::Vector3f p = R * centroids_[i] + t;
      if (p.z() < kMinDepthM) continue;
      const float uf = fx * p.x() / p.z() + cx, vf = fy * p.y() / p.z() + cy;
      if (!(uf >= 0.0f && vf >= 0.0f && uf < static_cast<float>(w) && vf < static_cast<float>(h)))
        continue;
      const float seen = view.near_m.at<float>(static_cast<int>(vf), static_cast<int>(uf));
      if (seen <= 0.0f) continue;
      const float m = margin + per_m2 * seen * seen;
      Element& e = elements_[i];
      if (e.in_view < 0xffff) ++e.in_view;
      if (p.z() < seen - m) {
        if (e.seen_through < cap) ++e.seen_through;
      } else if (p.z() <= seen + m && e.observed < 0xffff) {
        ++e.observed;
        e.first = std::min(e.first, index);
        e.last = index;  // views come in keyframe order
        if (has_mask && view.moving.at<std::uint8_t>(static_cast<int>(vf), static_cast<int>(uf)))
          ++e.masked;
      }
    }
  }

  /// The first verdict on every element: removed (seen through, or voted by masks) or a brief
  /// candidate for the plane test (its index goes to `brief`). Counts the removed ones and those
  /// removed by mask votes only. stamps: the keyframes' times (s), in view order.
  void judge(const VisibilityOptions& options, const std::vector<double>& stamps,
             const BesideMover& beside, std::vector<std::uint32_t>* brief, std::size_t* removed,
             std::size_t* mask_voted) {
    verdicts_.assign(elements_.size(), Verdict::kKept);
    for (std::uint32_t i = 0; i < elements_.size(); ++i) {
      const Element& e = elements_[i];
      const bool seen_through =
          e.seen_through >= static_cast<std::uint32_t>(std::max(1, options.min_views));
      const bool voted = options.mask_min_views > 0 && e.masked >= options.mask_min_views &&
                         e.masked >= options.mask_ratio * e.observed;
      if (seen_through || voted) {
        verdicts_[i] = Verdict::kRemoved;
        ++*removed;
        if (!seen_through) ++*mask_voted;
      } else if (briefUnderMask(e, options, stamps) || beside.holds(e, centroids_[i])) {
        verdicts_[i] = Verdict::kBrief;
        brief->push_back(i);
      }
    }
  }

  std::uint32_t find(std::uint64_t key) const { return index_.find(key); }
  std::uint64_t key(std::uint32_t i) const { return keys_[i]; }
  const Element& element(std::uint32_t i) const { return elements_[i]; }
  const Eigen::Vector3f& centroid(std::uint32_t i) const { return centroids_[i]; }
  Verdict verdict(std::uint32_t i) const { return verdicts_[i]; }
  std::size_t size() const { return elements_.size(); }
  std::size_t bytes() const {
    return elements_.capacity() * sizeof(Element) +
           centroids_.capacity() * sizeof(Eigen::Vector3f) +
           keys_.capacity() * sizeof(std::uint64_t) + index_.bytes() + verdicts_.capacity();
  }

 private:
  int part_;
  FlatIndex index_;
  std::vector<std::uint64_t> keys_;  ///< element i's voxel key
  std::vector<Element> elements_;
  std::vector<Eigen::Vector3f> centroids_;
  std::vector<Verdict> verdicts_;  ///< judge()'s
};

using SplitTable = std::array<ElementTable, 2>;

/// Whether element i of part `part` lies on a plane that the kept elements around it (within
/// kSupportRadiusM, seen by 2 keyframes or more, none of them a brief vote) span: the floor
/// that a mask took with a foot stays, the foot above it does not. (A flat mover's unmasked
/// rim can vouch for the rest of it.) Reads only: thread-safe after judge().
inline bool onConfirmedPlane(const SplitTable& table, int part, std::uint32_t i, float inv_voxel,
                             std::vector<Eigen::Vector3f>& support) {
  const int reach = std::max(1, static_cast<int>(std::lround(kSupportRadiusM * inv_voxel)));
  const std::uint64_t key = table[part].key(i);
  support.clear();
  for (int dz = -reach; dz <= reach; ++dz) {
    for (int dy = -reach; dy <= reach; ++dy) {
      for (int dx = -reach; dx <= reach; ++dx) {
        const std::uint64_t other = offsetKey(key, dx, dy, dz);
        const ElementTable& t = table[partOf(other)];
        const std::uint32_t j = t.find(other);
        if (j == FlatIndex::kMissing || other == key) continue;
        if (t.verdict(j) == Verdict::kKept && t.element(j).observed >= 2)
          support.push_back(t.centroid(j));
      }
    }
  }
  return liesOnPlane(support, table[part].centroid(i));
}

}  // namespace dynamap::vis
