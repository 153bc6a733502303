#include "dynamap/core/tracking/loop_closer.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace dynamap {
namespace {

/// The static features of `in` only (the rest is never evidence for a loop).
LoopKeyframe staticPart(const LoopKeyframeInput& in) {
  const std::size_t n = in.keypoints.size();
  if (static_cast<std::size_t>(in.descriptors.rows) != n || in.depth_m.size() != n ||
      in.is_static.size() != n || (!in.landmark_ids.empty() && in.landmark_ids.size() != n) ||
      (n > 0 && in.descriptors.type() != CV_8UC1)) {
    throw std::invalid_argument("LoopCloser::addKeyframe: per-keypoint vectors differ in size");
  }
  LoopKeyframe kf;
  kf.id = in.id;
  kf.T_W_C = in.T_W_C;
  for (std::size_t i = 0; i < n; ++i) {
    if (!in.is_static[i]) continue;
    kf.keypoints.push_back(in.keypoints[i]);
    kf.descriptors.push_back(in.descriptors.row(static_cast<int>(i)));
    kf.depth_m.push_back(in.depth_m[i]);
    kf.landmark_ids.push_back(in.landmark_ids.empty() ? LoopKeyframe::kNoLandmark
                                                      : in.landmark_ids[i]);
  }
  return kf;
}

}  // namespace

LoopCloser::LoopCloser(const PinholeCamera& camera, const TrackerConfig& tracker_config,
                       const LoopCloserConfig& config, TimingRecorder* timings)
    : camera_(camera),
      config_(config),
      timings_(timings),
      verifier_(camera, tracker_config, config.verify),
      recognizer_(config.place) {}

void LoopCloser::addKeyframe(LoopKeyframeInput keyframe) {
  PendingKeyframe pending{staticPart(keyframe), keyframe.generation};  // on the caller's thread
  std::lock_guard<std::mutex> lock(queue_mutex_);
  pending_.push_back(std::move(pending));
}

void LoopCloser::updatePose(std::uint64_t id, const Eigen::Isometry3d& T_W_C, int generation) {
  std::lock_guard<std::mutex> lock(queue_mutex_);
  pose_updates_.push_back({id, T_W_C, generation});
}

Eigen::Isometry3d LoopCloser::toCurrentGeneration(const Eigen::Isometry3d& T_W_C,
                                                  int generation) const {
  Eigen::Isometry3d T = T_W_C;
  for (std::size_t g = static_cast<std::size_t>(std::max(0, generation));
       g < generation_moves_.size(); ++g) {
    T = generation_moves_[g] * T;
  }
  return T;
}

void LoopCloser::drainQueues() {
  std::deque<PendingKeyframe> pending;
  std::vector<PoseInput> updates;
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    pending.swap(pending_);
    updates.swap(pose_updates_);
    for (auto& p : pending) p.keyframe.T_W_C = toCurrentGeneration(p.keyframe.T_W_C, p.generation);
    for (auto& u : updates) u.T_W_C = toCurrentGeneration(u.T_W_C, u.generation);
  }
  for (auto& p : pending) {
    const int index = static_cast<int>(database_.size());
    odometry_.push_back(database_.empty() ? Eigen::Isometry3d::Identity()
                                          : database_.back().T_W_C.inverse() * p.keyframe.T_W_C);
    index_of_[p.keyframe.id] = index;
    database_.push_back(std::move(p.keyframe));
  }
  for (const PoseInput& u : updates) {
    const auto it = index_of_.find(u.id);
    if (it == index_of_.end()) continue;
    const auto i = static_cast<std::size_t>(it->second);
    database_[i].T_W_C = u.T_W_C;
    if (i > 0) odometry_[i] = database_[i - 1].T_W_C.inverse() * u.T_W_C;
    if (i + 1 < database_.size()) odometry_[i + 1] = u.T_W_C.inverse() * database_[i + 1].T_W_C;
  }
}

std::optional<LoopConstraint> LoopCloser::detect() {
  const int first_new = recognizer_.size();
  drainQueues();
  std::optional<LoopConstraint> newest;
  for (int index = first_new; index < static_cast<int>(database_.size()); ++index) {
    ScopedStageTimer timer(timings_, "loop_detect");
    if (auto loop = detectFor(index)) newest = loop;
    const LoopKeyframe& kf = database_[static_cast<std::size_t>(index)];
    recognizer_.add(index, kf.descriptors);
    for (const std::uint64_t l : kf.landmark_ids) {
      if (l != LoopKeyframe::kNoLandmark) landmark_keyframes_[l].push_back(index);
    }
  }
  return newest;
}

std::vector<int> LoopCloser::covisible(int index) const {
  std::unordered_map<int, int> shared;
  for (const std::uint64_t l : database_[static_cast<std::size_t>(index)].landmark_ids) {
    const auto it = landmark_keyframes_.find(l);
    if (it == landmark_keyframes_.end()) continue;
    for (const int k : it->second) ++shared[k];
  }
  std::vector<int> out;
  for (const auto& [k, count] : shared) {
    if (count >= config_.min_shared_landmarks) out.push_back(k);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::optional<LoopConstraint> LoopCloser::detectFor(int index) {
  const int newest_allowed = index - config_.exclude_newest - 1;
  if (newest_allowed < 0) return std::nullopt;
  const LoopKeyframe& query = database_[static_cast<std::size_t>(index)];
  const std::vector<int> excluded = covisible(index);
  const auto allowed = [&](int k) {
    return k <= newest_allowed && !std::binary_search(excluded.begin(), excluded.end(), k);
  };
  const auto candidates = recognizer_.query(query.descriptors, allowed, config_.max_candidates);
  const double min_votes = config_.min_vote_share * query.descriptors.rows;
  for (const PlaceCandidate& c : candidates) {
    if (c.votes < min_votes) break;
    std::vector<const LoopKeyframe*> neighbours;
    for (int k = c.keyframe - config_.neighbour_span; k <= c.keyframe + config_.neighbour_span;
         ++k) {
      if (k != c.keyframe && k >= 0 && k <= newest_allowed) {
        neighbours.push_back(&database_[static_cast<std::size_t>(k)]);
      }
    }
    auto loop =
        verifier_.verify(query, database_[static_cast<std::size_t>(c.keyframe)], neighbours);
    if (loop) {
      loops_.push_back(*loop);
      return loop;
    }
  }
  return std::nullopt;
}

std::optional<LoopCorrection> LoopCloser::close() {
  if (loops_.size() == loops_closed_ || database_.empty()) return std::nullopt;
  ScopedStageTimer timer(timings_, "loop_close");
  PoseGraph graph;
  for (std::size_t i = 0; i < database_.size(); ++i) graph.addNode(database_[i].T_W_C, i == 0);
  const double deg = M_PI / 180.0;
  for (int i = 1; i < graph.size(); ++i) {
    graph.addEdge({i - 1, i, odometry_[static_cast<std::size_t>(i)], config_.odometry_sigma_m,
                   config_.odometry_sigma_deg * deg, false});
  }
  for (const LoopConstraint& l : loops_) {
    graph.addEdge({index_of_.at(l.match_id), index_of_.at(l.query_id), l.T_Cmatch_Cquery,
                   config_.loop_sigma_m, config_.loop_sigma_deg * deg, config_.robust_loop_edges});
  }
  if (!graph.optimize(config_.graph)) return std::nullopt;
  loops_closed_ = loops_.size();
  LoopCorrection out;
  for (std::size_t i = 0; i < database_.size(); ++i) {
    PoseCorrection c{database_[i].id, database_[i].T_W_C, graph.pose(static_cast<int>(i))};
    database_[i].T_W_C = c.T_W_C_after;
    out.keyframes.push_back(c);
  }
  std::lock_guard<std::mutex> lock(queue_mutex_);
  generation_moves_.push_back(out.keyframes.back().correction());
  out.generation = static_cast<int>(generation_moves_.size());
  return out;
}

}  // namespace dynamap
