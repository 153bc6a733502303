// `pcl_voxel`: an incrementally voxel-filtered cloud. Each keyframe's points are added to a hash
// map voxel key -> running centroid/colour (never re-filtering the whole map). For pose updates,
// each keyframe also keeps its points reduced to voxel centroids (camera frame); a moved
// keyframe marks the map dirty and export rebuilds the hash from those (cheap: reduced clouds).
#include <unordered_map>

#include <pcl/filters/statistical_outlier_removal.h>

#include "dynamap/mapping/backend_params.hpp"
#include "dynamap/mapping/plugin_api.hpp"
#include "dynamap/mapping/radix_sort.hpp"
#include "pcl_cloud_io.hpp"
#include "voxel_key.hpp"

namespace dynamap {
namespace {

using VoxelMap = std::unordered_map<std::uint64_t, plugin::VoxelAccum>;

class PclVoxelBackend final : public MapBackend {
 public:
  explicit PclVoxelBackend(const BackendParams& params) {
    ParamReader reader("pcl_voxel", params);
    voxel_size_m_ = reader.getDouble("voxel_size_m", 0.01, 0.001, 1.0);
    min_points_ = reader.getInt("min_points_per_voxel", 1, 1, 1000000);
    sor_k_ = reader.getInt("sor_k", 0, 0, 1000);
    sor_stddev_ = reader.getDouble("sor_stddev", 1.0, 0.0, 100.0);
    reader.finish();
    inv_voxel_ = static_cast<float>(1.0 / voxel_size_m_);
  }

  void integrate(const KeyframeView& view) override {
    const Eigen::Isometry3f T = view.T_W_C.cast<float>();
    const auto& pts = *view.points_C;
    // Sort the keyframe's points by world voxel: one hash access per distinct voxel, and the
    // same runs give the keyframe's own reduced cloud (kept in the camera frame for pose updates).
    std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(pts.size());
    std::vector<Eigen::Vector3f> p_W(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) {
      p_W[i] = T * pts[i];
      keyed[i] = {plugin::voxelKey(p_W[i], inv_voxel_), static_cast<std::uint32_t>(i)};
    }
    radixSortByKey(keyed, scratch_, [](const auto& k) { return k.first; });
    Keyframe kf;
    kf.T_W_C = view.T_W_C;
    kf.T_integrated = view.T_W_C;
    const Eigen::Isometry3f T_C_W = T.inverse();
    for (std::size_t b = 0; b < keyed.size();) {
      plugin::VoxelAccum run;
      std::size_t e = b;
      for (; e < keyed.size() && keyed[e].first == keyed[b].first; ++e) {
        run.add(p_W[keyed[e].second], (*view.colors)[keyed[e].second].data());
      }
      plugin::VoxelAccum& dst = map_[keyed[b].first];
      dst.sum += run.sum;
      for (int k = 0; k < 3; ++k) dst.rgb_sum[k] += run.rgb_sum[k];
      dst.count += run.count;
      run.sum = (T_C_W * (run.sum / static_cast<float>(run.count))) * static_cast<float>(run.count);
      kf.voxels.push_back(run);
      b = e;
    }
    keyframes_[view.id] = std::move(kf);
  }

  void updatePose(std::uint64_t keyframe_id, const Eigen::Isometry3d& T_W_C) override {
    auto it = keyframes_.find(keyframe_id);
    if (it == keyframes_.end()) return;
    it->second.T_W_C = T_W_C;
    dirty_ = dirty_ || !it->second.T_W_C.isApprox(it->second.T_integrated, 1e-9);
  }
  PoseUpdateMode poseUpdateMode() const override { return PoseUpdateMode::kInPlace; }
  void reset() override {
    map_.clear();
    keyframes_.clear();
    dirty_ = false;
  }

  void exportMap(const std::string& dir) override {
    if (dirty_) rebuild();
    pcl::PointCloud<pcl::PointXYZRGB>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZRGB>);
    cloud->reserve(map_.size());
    for (const auto& kv : map_) {
      const plugin::VoxelAccum& a = kv.second;
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
    s.elements = map_.size();
    std::size_t kf_voxels = 0;
    for (const auto& kv : keyframes_) kf_voxels += kv.second.voxels.size();
    const std::size_t node = sizeof(plugin::VoxelAccum) + sizeof(std::uint64_t) + 2 * sizeof(void*);
    s.memory_bytes = map_.size() * node + kf_voxels * sizeof(plugin::VoxelAccum);
    s.element_kind = "voxels";
    return s;
  }

 private:
  struct Keyframe {
    Eigen::Isometry3d T_W_C;
    Eigen::Isometry3d T_integrated;
    std::vector<plugin::VoxelAccum> voxels;  ///< camera frame
  };

  void rebuild() {
    map_.clear();
    for (auto& kv : keyframes_) {
      const Eigen::Isometry3f T = kv.second.T_W_C.cast<float>();
      for (const plugin::VoxelAccum& a : kv.second.voxels) {
        const Eigen::Vector3f p_W = T * (a.sum / static_cast<float>(a.count));
        plugin::VoxelAccum& dst = map_[plugin::voxelKey(p_W, inv_voxel_)];
        dst.sum += p_W * static_cast<float>(a.count);
        for (int k = 0; k < 3; ++k) dst.rgb_sum[k] += a.rgb_sum[k];
        dst.count += a.count;
      }
      kv.second.T_integrated = kv.second.T_W_C;
    }
    dirty_ = false;
  }

  double voxel_size_m_ = 0.01;
  float inv_voxel_ = 100.0f;
  int min_points_ = 1;
  int sor_k_ = 0;
  double sor_stddev_ = 1.0;
  VoxelMap map_;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> scratch_;  ///< integrate()'s sort
  std::unordered_map<std::uint64_t, Keyframe> keyframes_;
  bool dirty_ = false;
};

}  // namespace
}  // namespace dynamap

DYNAMAP_DEFINE_BACKEND(dynamap::PclVoxelBackend)
