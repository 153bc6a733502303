#include "dynamap/core/tracking/local_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <unordered_set>

#include "dynamap/core/tracking/loop_closer.hpp"

namespace dynamap {

std::uint64_t LocalMap::addLandmark(const Eigen::Vector3d& p_W, const cv::Mat& descriptor) {
  std::lock_guard<std::mutex> lock(mutex_);
  landmarks_.push_back(Landmark{p_W, descriptor.clone()});
  return landmarks_.size() - 1;
}

std::uint64_t LocalMap::addKeyframe(double timestamp_s, const Eigen::Isometry3d& T_W_C,
                                    std::vector<KeyframeObservation> observations,
                                    double masked_share, cv::Mat static_cells) {
  std::lock_guard<std::mutex> lock(mutex_);
  MapKeyframe kf;
  kf.id = keyframes_.size();
  kf.timestamp_s = timestamp_s;
  kf.T_W_C = T_W_C;
  kf.observations = std::move(observations);
  kf.masked_share = masked_share;
  kf.static_cells = std::move(static_cells);
  for (const auto& o : kf.observations) ++landmarks_[o.landmark_id].keyframes;
  keyframes_.push_back(std::move(kf));
  return keyframes_.back().id;
}

std::size_t LocalMap::keyframeCount() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return keyframes_.size();
}

bool LocalMap::cull(std::uint64_t id, std::uint64_t parent) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (id == 0 || parent >= id || id >= keyframes_.size()) return false;
  MapKeyframe& kf = keyframes_[id];
  const MapKeyframe& to = keyframes_[parent];
  if (kf.culled || kf.loaded || to.culled) return false;
  kf.culled = true;
  kf.parent = parent;
  kf.T_parent_C = to.T_W_C.inverse() * kf.T_W_C;
  keyframes_[parent].culled_children.push_back(id);
  culled_.push_back(id);
  return true;
}

bool LocalMap::isCulled(std::uint64_t id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return keyframes_.at(id).culled;
}

void LocalMap::followParentsLocked(std::vector<PoseUpdate>* updates) {
  for (const auto id : culled_) {
    MapKeyframe& kf = keyframes_[id];
    const Eigen::Isometry3d T_W_C = keyframes_[kf.parent].T_W_C * kf.T_parent_C;
    if (T_W_C.isApprox(kf.T_W_C, 1e-12)) continue;
    kf.T_W_C = T_W_C;
    if (updates != nullptr) updates->push_back(PoseUpdate{id, T_W_C});
  }
}

Eigen::Isometry3d LocalMap::keyframePose(std::uint64_t id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return keyframes_.at(id).T_W_C;
}

void LocalMap::markBad(const std::vector<std::uint64_t>& ids) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const auto id : ids) {
    if (id < landmarks_.size()) landmarks_[id].bad = true;
  }
}

bool LocalMap::isBad(std::uint64_t id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return id < landmarks_.size() && landmarks_[id].bad;
}

void LocalMap::landmarkPositions(const std::vector<std::uint64_t>& ids,
                                 std::vector<Eigen::Vector3d>& out) const {
  std::lock_guard<std::mutex> lock(mutex_);
  out.resize(ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i) out[i] = landmarks_[ids[i]].p_W;
}

void LocalMap::descriptorsOf(const std::vector<std::uint64_t>& ids, cv::Mat& descriptors,
                             std::vector<std::uint8_t>& bad) const {
  std::lock_guard<std::mutex> lock(mutex_);
  descriptors = cv::Mat(static_cast<int>(ids.size()), 32, CV_8UC1, cv::Scalar(0));
  bad.assign(ids.size(), 0);
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const Landmark& lm = landmarks_[ids[i]];
    if (lm.descriptor.cols == 32) lm.descriptor.copyTo(descriptors.row(static_cast<int>(i)));
    bad[i] = lm.bad || lm.descriptor.cols != 32 ? 1 : 0;
  }
}

void LocalMap::keyframeCounts(const std::vector<std::uint64_t>& ids, std::vector<int>& out) const {
  std::lock_guard<std::mutex> lock(mutex_);
  out.resize(ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i) out[i] = landmarks_[ids[i]].keyframes;
}

// Keyframes older than `first`, made `min_age_s` or more before the newest, that see the
// window's landmarks (a revisit re-found them), the `limit` sharing the most, oldest first: held
// fixed, they keep the window's landmarks where the old keyframes put them, so a revisit's window
// cannot move the old map's landmarks away from the keyframes that made them.
std::vector<int> LocalMap::olderCovisibleLocked(
    int first, int limit, double min_age_s,
    const std::unordered_map<std::uint64_t, int>& lm_index) const {
  std::vector<std::pair<int, int>> shared;  // (landmarks shared, keyframe)
  if (limit <= 0 || keyframes_.empty()) return {};
  const double newest_s = keyframes_.back().timestamp_s;
  for (int k = 0; k < first; ++k) {
    const auto& kf = keyframes_[static_cast<std::size_t>(k)];
    if (kf.culled || kf.timestamp_s > newest_s - min_age_s) continue;
    int count = 0;
    for (const auto& o : kf.observations) count += lm_index.count(o.landmark_id) != 0 ? 1 : 0;
    if (count > 0) shared.emplace_back(count, k);
  }
  const auto keep = std::min(shared.size(), static_cast<std::size_t>(limit));
  std::partial_sort(shared.begin(), shared.begin() + static_cast<std::ptrdiff_t>(keep),
                    shared.end(), [](const auto& a, const auto& b) {
                      return a.first != b.first ? a.first > b.first : a.second < b.second;
                    });
  std::vector<int> ids;
  for (std::size_t i = 0; i < keep; ++i) ids.push_back(shared[i].second);
  std::sort(ids.begin(), ids.end());
  return ids;
}

BaWindow LocalMap::snapshotWindow(int window, int fixed, int older_covisible,
                                  double older_min_age_s) const {
  std::lock_guard<std::mutex> lock(mutex_);
  BaWindow w;
  w.generation = generation_;
  const int n = static_cast<int>(keyframes_.size());
  const int first_opt = std::max(0, n - window);
  const int first = std::max(0, first_opt - window);
  const int first_free = std::max(first_opt + fixed, 1);  // keyframe 0 defines the world
  if (first_free >= n) return w;
  // A keyframe's own observations, then those of the keyframes culled into it (attached).
  const auto each_observation = [this](const MapKeyframe& kf, const auto& fn) {
    for (const auto& o : kf.observations) fn(o, static_cast<const MapKeyframe*>(nullptr));
    for (const auto child : kf.culled_children) {
      for (const auto& o : keyframes_[child].observations) fn(o, &keyframes_[child]);
    }
  };
  std::unordered_map<std::uint64_t, int> lm_index;
  for (int k = first_free; k < n; ++k) {
    const auto& kf = keyframes_[static_cast<std::size_t>(k)];
    if (kf.culled) continue;
    each_observation(kf, [&](const KeyframeObservation& o, const MapKeyframe*) {
      if (landmarks_[o.landmark_id].bad) return;
      if (lm_index.emplace(o.landmark_id, static_cast<int>(w.landmark_ids.size())).second) {
        w.landmark_ids.push_back(o.landmark_id);
        w.points.push_back(landmarks_[o.landmark_id].p_W);
      }
    });
  }
  std::vector<int> observers =
      olderCovisibleLocked(first, older_covisible, older_min_age_s, lm_index);
  for (int k = first; k < n; ++k) observers.push_back(k);
  for (const int k : observers) {
    const auto& kf = keyframes_[static_cast<std::size_t>(k)];
    if (kf.culled) continue;
    const int kf_index = static_cast<int>(w.keyframe_ids.size());
    const std::size_t observations_before = w.observations.size();
    const MapKeyframe* last_child = nullptr;
    each_observation(kf, [&](const KeyframeObservation& o, const MapKeyframe* child) {
      auto it = lm_index.find(o.landmark_id);
      if (it == lm_index.end()) return;
      if (child != nullptr && child != last_child) {
        w.attached.push_back(child->T_parent_C.inverse());
        last_child = child;
      }
      const int attached = child == nullptr ? -1 : static_cast<int>(w.attached.size()) - 1;
      w.observations.push_back({kf_index, it->second, o.px, o.depth_m, attached});
    });
    if (w.observations.size() == observations_before) continue;
    w.keyframe_ids.push_back(kf.id);
    w.poses.push_back(kf.T_W_C);
    w.fixed.push_back(k < first_free || kf.loaded ? 1 : 0);  // a loaded map stays put
    w.timestamps_s.push_back(kf.loaded ? std::numeric_limits<double>::quiet_NaN() : kf.timestamp_s);
  }
  return w;
}

std::vector<PoseUpdate> LocalMap::apply(const BaWindow& solved) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<PoseUpdate> updates;
  if (solved.generation != generation_) return updates;
  for (std::size_t k = 0; k < solved.keyframe_ids.size(); ++k) {
    if (solved.fixed[k]) continue;
    keyframes_[solved.keyframe_ids[k]].T_W_C = solved.poses[k];
    updates.push_back(PoseUpdate{solved.keyframe_ids[k], solved.poses[k]});
  }
  for (std::size_t i = 0; i < solved.landmark_ids.size(); ++i) {
    landmarks_[solved.landmark_ids[i]].p_W = solved.points[i];
  }
  followParentsLocked(&updates);
  return updates;
}

std::vector<PoseUpdate> LocalMap::applyLoopCorrection(const LoopCorrection& correction) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<PoseUpdate> updates;
  if (correction.keyframes.empty()) return updates;
  // Per keyframe: the correction that moves it (left-multiplied, so a BA refinement made since
  // the loop closer saw the pose is kept).
  std::vector<Eigen::Isometry3d> move_of(keyframes_.size(),
                                         correction.keyframes.back().correction());
  for (const PoseCorrection& c : correction.keyframes) {
    if (c.id < move_of.size()) move_of[c.id] = c.correction();
  }
  constexpr std::size_t kNoAnchor = ~std::size_t{0};
  std::vector<std::size_t> anchor(landmarks_.size(), kNoAnchor);
  for (std::size_t k = 0; k < keyframes_.size(); ++k) {
    for (const auto& o : keyframes_[k].observations) {
      if (anchor[o.landmark_id] == kNoAnchor) anchor[o.landmark_id] = k;
    }
  }
  for (std::size_t i = 0; i < landmarks_.size(); ++i) {
    if (anchor[i] != kNoAnchor) landmarks_[i].p_W = move_of[anchor[i]] * landmarks_[i].p_W;
  }
  updates.reserve(keyframes_.size());
  for (std::size_t k = 0; k < keyframes_.size(); ++k) {
    keyframes_[k].T_W_C = move_of[k] * keyframes_[k].T_W_C;
  }
  followParentsLocked(nullptr);  // every keyframe is listed below anyway
  for (const auto& kf : keyframes_) updates.push_back(PoseUpdate{kf.id, kf.T_W_C});
  generation_ = correction.generation;
  return updates;
}

int LocalMap::generation() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return generation_;
}

std::vector<std::uint64_t> LocalMap::newestKeyframes(int count) const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<std::uint64_t> newest;
  const int n = static_cast<int>(keyframes_.size());
  for (int k = n - 1; k >= std::max(0, n - count); --k) {
    if (!keyframes_[static_cast<std::size_t>(k)].culled)
      newest.push_back(static_cast<std::uint64_t>(k));
  }
  return newest;
}

std::vector<KeyframeInfo> LocalMap::keyframes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<KeyframeInfo> out;
  out.reserve(keyframes_.size());
  for (const auto& kf : keyframes_) {
    out.push_back(KeyframeInfo{kf.id, kf.timestamp_s, kf.T_W_C, kf.culled});
  }
  return out;
}

std::vector<std::uint64_t> LocalMap::keyframesNear(const Eigen::Isometry3d& T_W_C,
                                                   double max_translation_m,
                                                   double max_rotation_deg, double latest_s) const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<std::pair<double, std::uint64_t>> near;
  const double max_rotation_rad = max_rotation_deg * M_PI / 180.0;
  for (const auto& kf : keyframes_) {
    if (kf.culled || (kf.timestamp_s > latest_s && !kf.loaded)) continue;
    const Eigen::Isometry3d T_kf_C = kf.T_W_C.inverse() * T_W_C;
    const double distance = std::max(T_kf_C.translation().norm() / max_translation_m,
                                     Eigen::AngleAxisd(T_kf_C.linear()).angle() / max_rotation_rad);
    if (distance <= 1.0) near.emplace_back(distance, kf.id);
  }
  std::sort(near.begin(), near.end());
  std::vector<std::uint64_t> ids;
  ids.reserve(near.size());
  for (const auto& n : near) ids.push_back(n.second);
  return ids;
}

LandmarkCandidates LocalMap::landmarksOf(const std::vector<std::uint64_t>& keyframe_ids) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return landmarksOfLocked(keyframe_ids);
}

LandmarkCandidates LocalMap::landmarksOfLocked(
    const std::vector<std::uint64_t>& keyframe_ids) const {
  LandmarkCandidates out;
  std::unordered_set<std::uint64_t> seen;
  const auto add = [&](const MapKeyframe& kf) {
    for (const auto& o : kf.observations) {
      if (!seen.insert(o.landmark_id).second) continue;
      const Landmark& lm = landmarks_[o.landmark_id];
      if (lm.descriptor.empty() || lm.bad) continue;
      out.ids.push_back(o.landmark_id);
      out.points.push_back(lm.p_W);
      out.descriptors.push_back(lm.descriptor);
    }
  };
  for (const auto k : keyframe_ids) {
    const MapKeyframe& kf = keyframes_.at(k);
    add(kf);
    for (const auto child : kf.culled_children) add(keyframes_[child]);
  }
  return out;
}

MapContents LocalMap::contents() const {
  std::lock_guard<std::mutex> lock(mutex_);
  MapContents out{landmarks_, {}};
  out.keyframes.reserve(keyframes_.size() - culled_.size());
  for (const auto& kf : keyframes_) {
    if (kf.culled) continue;
    out.keyframes.push_back(kf);
    out.keyframes.back().id = out.keyframes.size() - 1;
  }
  return out;
}

void LocalMap::restore(MapContents contents) {
  for (auto& kf : contents.keyframes) kf.loaded = true;
  // The landmarks keep the saved runs' keyframe counts: the motion filter's pose prior
  // (Tracker::Impl::priorPose()) takes those seen by static_prior_min_keyframes from the
  // tracks, which the last frame's pose kept, in this run. A landmark on a chair moved since
  // the map was saved is not found again where it was, or is the prior's RANSAC outlier.
  std::lock_guard<std::mutex> lock(mutex_);
  landmarks_ = std::move(contents.landmarks);
  keyframes_ = std::move(contents.keyframes);
  culled_.clear();
}

std::size_t LocalMap::observationCount(std::uint64_t keyframe_id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return keyframes_.at(keyframe_id).observations.size();
}

std::vector<CoverageView> LocalMap::coverageViews(
    const std::vector<std::uint64_t>& keyframe_ids) const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<CoverageView> views;
  views.reserve(keyframe_ids.size());
  for (const auto id : keyframe_ids) {
    const MapKeyframe& kf = keyframes_.at(id);
    views.push_back(CoverageView{kf.T_W_C, kf.static_cells});
  }
  return views;
}

}  // namespace dynamap
