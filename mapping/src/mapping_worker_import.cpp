// MappingWorker::importPoints(): a saved map's points as the backend's first content.
#include "dynamap/mapping/mapping_worker.hpp"

namespace dynamap {

bool MappingWorker::importPoints(const std::vector<Eigen::Vector3f>& p_W,
                                 const std::vector<std::array<std::uint8_t, 3>>& colors) {
  std::lock_guard<std::mutex> lock(backend_mutex_);
  if (backend_->poseUpdateMode() != PoseUpdateMode::kInPlace || !backend_->needsPoints()) {
    return false;
  }
  std::vector<std::array<std::uint8_t, 3>> rgb = colors;
  rgb.resize(p_W.size(), {200, 200, 200});  // a cloud without colours: light grey
  KeyframeView view;
  view.id = kLoadedMapId;
  view.camera = &camera_;  // identity pose: the points are already in the world frame
  view.points_C = &p_W;
  view.colors = &rgb;
  backend_->integrate(view);
  ++supplements_;  // not a keyframe of this run: stats() leaves it out
  return true;
}

}  // namespace dynamap
