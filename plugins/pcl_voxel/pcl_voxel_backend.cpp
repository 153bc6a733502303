// `pcl_voxel`: a voxel-filtered cloud that follows pose corrections. Each keyframe's points
// are reduced to voxel centroids (grouped by world voxel at integration) and kept compactly in
// its camera frame (keyframe_voxels.hpp); the map is those centroids placed by the keyframes'
// current poses and merged by world voxel, at export. No whole-map structure lives between
// exports: memory is the keyframes' reduced clouds (the newest resident_keyframes in RAM, the
// others in a temporary file), and a pose update costs nothing. A saved map's cloud.ply
// (importMap()) is one more block, in the world frame, of no keyframe.
#include <array>
#include <deque>
#include <map>
#include <memory>
#include <optional>

#include <pcl/filters/statistical_outlier_removal.h>

#include "dynamap/mapping/backend_params.hpp"
#include "dynamap/mapping/in_two.hpp"
#include "dynamap/mapping/plugin_api.hpp"
#include "dynamap/mapping/voxel_block_index.hpp"
#include "keyframe_voxels.hpp"
#include "pcl_cloud_io.hpp"
#include "voxel_key.hpp"

namespace dynamap {
namespace {

class PclVoxelBackend final : public MapBackend {
 public:
  explicit PclVoxelBackend(const BackendParams& params) {
    ParamReader reader("pcl_voxel", params);
    voxel_size_m_ = reader.getDouble("voxel_size_m", 0.01, 0.001, 1.0);
    min_points_ = reader.getInt("min_points_per_voxel", 1, 1, 1000000);
    sor_k_ = reader.getInt("sor_k", 0, 0, 1000);
    sor_stddev_ = reader.getDouble("sor_stddev", 1.0, 0.0, 100.0);
    resident_keyframes_ = reader.getInt("resident_keyframes", 32, 0, 1000000);
    reader.finish();
    inv_voxel_ = static_cast<float>(1.0 / voxel_size_m_);
  }

  void integrate(const KeyframeView& view) override {
    keyframes_.insert_or_assign(
        view.id, Keyframe{view.T_W_C, reduce(*view.points_C, *view.colors, view.T_W_C)});
    elements_.reset();
    spillOldKeyframes(view.id);
  }

  void updatePose(std::uint64_t keyframe_id, const Eigen::Isometry3d& T_W_C) override {
    auto it = keyframes_.find(keyframe_id);
    if (it == keyframes_.end()) return;
    it->second.T_W_C = T_W_C;
    elements_.reset();
  }
  PoseUpdateMode poseUpdateMode() const override { return PoseUpdateMode::kInPlace; }
  void reset() override {
    keyframes_.clear();
    resident_.clear();
    elements_.reset();
  }
  /// The saved cloud.ply's points fall back into their voxels, one block of no keyframe.
  bool importMap(const std::string& dir) override {
    const PlyData ply = plugin::loadCloudPly(dir);
    const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
    loaded_.emplace(Keyframe{identity, reduce(ply.vertices, ply.colors, identity)});
    elements_.reset();
    return true;
  }

  void exportMap(const std::string& dir) override {
    pcl::PointCloud<pcl::PointXYZRGB>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZRGB>);
    const std::vector<plugin::VoxelAccum> voxels = mergedVoxels();
    elements_ = voxels.size();
    cloud->reserve(voxels.size());
    for (const plugin::VoxelAccum& a : voxels) {
      if (a.count < static_cast<std::uint32_t>(min_points_)) continue;
      const std::array<std::uint8_t, 3> rgb = {static_cast<std::uint8_t>(a.rgb_sum[0] / a.count),
                                               static_cast<std::uint8_t>(a.rgb_sum[1] / a.count),
                                               static_cast<std::uint8_t>(a.rgb_sum[2] / a.count)};
      cloud->push_back(plugin::makePoint(a.sum / static_cast<float>(a.count), rgb));
    }
    if (sor_k_ > 0 && cloud->size() > static_cast<std::size_t>(sor_k_)) {
      pcl::StatisticalOutlierRemoval<pcl::PointXYZRGB> sor;
      sor.setInputCloud(cloud);
      sor.setMeanK(sor_k_);
      sor.setStddevMulThresh(sor_stddev_);
      pcl::PointCloud<pcl::PointXYZRGB>::Ptr filtered(new pcl::PointCloud<pcl::PointXYZRGB>);
      sor.filter(*filtered);
      cloud = filtered;
    }
    plugin::saveCloudPlyPcd(*cloud, dir);
  }

  MapStats stats() const override {
    MapStats s;
    s.keyframes = keyframes_.size();
    if (!elements_) elements_ = distinctVoxels();
    s.elements = *elements_;
    forEachBlock([&s](const Keyframe& kf) { s.memory_bytes += kf.voxels.bytes(); });
    s.element_kind = "voxels";
    return s;
  }

 private:
  struct Keyframe {
    Eigen::Isometry3d T_W_C;
    plugin::KeyframeVoxels voxels;
  };

  /// Points (camera frame) reduced to their world voxels' centroids, kept in the camera frame,
  /// the voxels in the order of their first point (a surface walk: neighbours stay near).
  plugin::KeyframeVoxels reduce(const std::vector<Eigen::Vector3f>& pts,
                                const std::vector<std::array<std::uint8_t, 3>>& colors,
                                const Eigen::Isometry3d& T_W_C) const {
    const Eigen::Isometry3f T = T_W_C.cast<float>();
    VoxelBlockIndex index(pts.size() / 4);
    std::vector<plugin::VoxelAccum> voxels_C;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const std::uint64_t key = plugin::voxelKey(T * pts[i], inv_voxel_);
      const auto slot = index.tryEmplace(key, static_cast<std::uint32_t>(voxels_C.size()));
      if (slot.second) voxels_C.emplace_back();
      voxels_C[slot.first].add(pts[i], colors[i].data());
    }
    return plugin::KeyframeVoxels(voxels_C);
  }

  /// The imported map, then the keyframes in id order.
  template <typename F>
  void forEachBlock(F&& f) const {
    if (loaded_) f(*loaded_);
    for (const auto& kv : keyframes_) f(kv.second);
  }

  /// Beyond the newest resident_keyframes integrated, the oldest keyframe's voxels go to the
  /// spill file (0: all stay in RAM).
  void spillOldKeyframes(std::uint64_t newest) {
    if (resident_keyframes_ <= 0) return;
    resident_.push_back(newest);
    while (resident_.size() > static_cast<std::size_t>(resident_keyframes_)) {
      const auto it = keyframes_.find(resident_.front());
      resident_.pop_front();
      if (it == keyframes_.end()) continue;
      if (!spill_) spill_ = std::make_unique<plugin::SpillFile<plugin::CompactVoxel>>();
      it->second.voxels.spill(*spill_);
    }
  }

  /// Calls f(world voxel key, centroid_W, rgb, count) for every voxel of the imported map and
  /// the keyframes (forEachBlock()'s order).
  template <typename F>
  void forEachPlacedVoxel(F&& f) const {
    std::vector<plugin::CompactVoxel> buffer;
    forEachBlock([&](const Keyframe& kf) {
      const Eigen::Isometry3f T = kf.T_W_C.cast<float>();
      kf.voxels.forEach(buffer,
                        [&](const Eigen::Vector3f& p_C, const std::uint8_t* rgb, std::uint32_t n) {
                          const Eigen::Vector3f p_W = T * p_C;
                          f(plugin::voxelKey(p_W, inv_voxel_), p_W, rgb, n);
                        });
    });
  }

  std::size_t placedVoxelCount() const {
    std::size_t n = 0;
    forEachBlock([&n](const Keyframe& kf) { n += kf.voxels.size(); });
    return n;
  }

  /// The map: every keyframe's voxels at its current pose, merged by world voxel. Two halves
  /// of the world's voxels (by a hash of their 4 x 4 x 4 block) are merged at once on two
  /// threads (inTwo), each in the order of their first keyframe, the first half first. (With TBB
  /// here the reload tests ran ~500 x slower under TSan than in Release; `points` ~20 x.)
  std::vector<plugin::VoxelAccum> mergedVoxels() const {
    std::array<std::vector<plugin::VoxelAccum>, kMergeHalves> merged;
    inTwo([&](int half) {
      VoxelBlockIndex index(expectedVoxels());
      std::vector<plugin::VoxelAccum>& out = merged[static_cast<std::size_t>(half)];
      out.reserve(expectedVoxels());
      forEachPlacedVoxel([&](std::uint64_t key, const Eigen::Vector3f& p_W, const std::uint8_t* rgb,
                             std::uint32_t n) {
        if (halfOf(key) != half) return;
        const auto slot = index.tryEmplace(key, static_cast<std::uint32_t>(out.size()));
        if (slot.second) out.emplace_back();
        out[slot.first].add(p_W, rgb, n);
      });
    });
    for (int h = 1; h < kMergeHalves; ++h) {
      merged[0].insert(merged[0].end(), merged[h].begin(), merged[h].end());
    }
    return std::move(merged[0]);
  }

  std::size_t distinctVoxels() const {
    std::array<std::size_t, kMergeHalves> count{};
    inTwo([&](int half) {
      VoxelBlockIndex index(expectedVoxels());
      forEachPlacedVoxel(
          [&](std::uint64_t key, const Eigen::Vector3f&, const std::uint8_t*, std::uint32_t) {
            if (halfOf(key) == half) index.tryEmplace(key, 0);
          });
      count[static_cast<std::size_t>(half)] = index.size();
    });
    std::size_t n = 0;
    for (const std::size_t c : count) n += c;
    return n;
  }

  static constexpr int kMergeHalves = 2;  // inTwo()
  static int halfOf(std::uint64_t key) {  // Fibonacci hash of the block, top bit
    return static_cast<int>((VoxelBlockIndex::blockOf(key) * 0x9E3779B97F4A7C15ull) >> 63);
  }
  /// Distinct voxels expected in one half (5 % margin): the map's if known, else 2/3 of the
  /// placed ones. Too few costs a regrowth of the half's index and voxels.
  std::size_t expectedVoxels() const {
    const std::size_t all = elements_ ? *elements_ : placedVoxelCount() * 2 / 3;
    return all / kMergeHalves + all / 20;
  }

  double voxel_size_m_ = 0.01;
  float inv_voxel_ = 100.0f;
  int min_points_ = 1;
  int sor_k_ = 0;
  double sor_stddev_ = 1.0;
  int resident_keyframes_ = 32;
  std::unique_ptr<plugin::SpillFile<plugin::CompactVoxel>> spill_;  ///< made at the first spill
  std::map<std::uint64_t, Keyframe> keyframes_;
  std::optional<Keyframe> loaded_;      ///< importMap()'s voxels (world frame), of no keyframe
  std::deque<std::uint64_t> resident_;  ///< keyframes in RAM, oldest first
  mutable std::optional<std::size_t> elements_;  ///< distinct voxels, until the map changes
};

}  // namespace
}  // namespace dynamap

DYNAMAP_DEFINE_BACKEND(dynamap::PclVoxelBackend)
