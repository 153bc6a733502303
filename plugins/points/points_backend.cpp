// `points`: raw stitching of keyframe clouds. Keeps each keyframe's static points in the camera
// frame, so pose updates only change the stored pose; export transforms and concatenates. A
// saved map's cloud.ply (importMap()) is kept in the world frame beside them.
#include <functional>
#include <unordered_map>
#include <vector>

#include "dynamap/mapping/backend_params.hpp"
#include "dynamap/mapping/plugin_api.hpp"
#include "pcl_cloud_io.hpp"

namespace dynamap {
namespace {

class PointsBackend final : public MapBackend {
 public:
  explicit PointsBackend(const BackendParams& params) {
    ParamReader reader("points", params);
    keep_every_ = reader.getInt("keep_every", 1, 1, 1000);
    reader.finish();
  }

  void integrate(const KeyframeView& view) override {
    Keyframe kf;
    kf.T_W_C = view.T_W_C;
    const auto& pts = *view.points_C;
    for (std::size_t i = 0; i < pts.size(); i += static_cast<std::size_t>(keep_every_)) {
      kf.points_C.push_back(pts[i]);
      kf.colors.push_back((*view.colors)[i]);
    }
    const std::size_t n = kf.points_C.size();
    if (!keyframes_.emplace(view.id, std::move(kf)).second) return;  // integrated already
    order_.push_back(view.id);
    total_points_ += n;
  }

  void updatePose(std::uint64_t keyframe_id, const Eigen::Isometry3d& T_W_C) override {
    auto it = keyframes_.find(keyframe_id);
    if (it != keyframes_.end()) it->second.T_W_C = T_W_C;
  }
  PoseUpdateMode poseUpdateMode() const override { return PoseUpdateMode::kInPlace; }
  void reset() override {
    keyframes_.clear();
    order_.clear();
    total_points_ = loaded_.points_C.size();
  }
  bool importMap(const std::string& dir) override {
    PlyData ply = plugin::loadCloudPly(dir);
    total_points_ = total_points_ - loaded_.points_C.size() + ply.vertices.size();
    loaded_.points_C = std::move(ply.vertices);  // world frame: the identity pose
    loaded_.colors = std::move(ply.colors);
    return true;
  }

  // Each keyframe's points are moved into the world frame and written as they are made: no
  // copy of the whole cloud (at 14 M points it was 0.6 GB, the run's peak memory).
  void exportMap(const std::string& dir) override {
    const auto pieces = [this](const std::function<void(const plugin::CloudPiece&)>& emit) {
      std::vector<Eigen::Vector3f> world;
      const auto piece = [&](const Keyframe& kf) {
        const Eigen::Isometry3f T = kf.T_W_C.cast<float>();
        world.resize(kf.points_C.size());
        for (std::size_t i = 0; i < kf.points_C.size(); ++i) world[i] = T * kf.points_C[i];
        emit({world.data(), kf.colors.data(), world.size()});
      };
      piece(loaded_);
      for (const std::uint64_t id : order_) piece(keyframes_.at(id));
    };
    plugin::saveCloudPlyPcd(total_points_, pieces, dir);
  }

  MapStats stats() const override {
    MapStats s;
    s.keyframes = keyframes_.size();
    s.elements = total_points_;
    s.memory_bytes = total_points_ * (sizeof(Eigen::Vector3f) + 3);
    s.element_kind = "points";
    return s;
  }

 private:
  struct Keyframe {
    Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
    std::vector<Eigen::Vector3f> points_C;
    std::vector<std::array<std::uint8_t, 3>> colors;
  };
  int keep_every_ = 1;
  std::unordered_map<std::uint64_t, Keyframe> keyframes_;
  std::vector<std::uint64_t> order_;
  Keyframe loaded_;  ///< importMap()'s points, of no keyframe
  std::size_t total_points_ = 0;
};

}  // namespace
}  // namespace dynamap

DYNAMAP_DEFINE_BACKEND(dynamap::PointsBackend)
