// Loop closure in the tracker (tracking.loop_closure): keyframes' static features to the loop
// thread, its corrections into the map and the tracker's state.
#include <cmath>

#include "dynamap/core/tracking/depth_sampling.hpp"
#include "dynamap/core/tracking/tracker_impl.hpp"

namespace dynamap {
namespace {

bool setAt(const cv::Mat& mask, const cv::Point2f& p) {
  if (mask.empty()) return false;
  const int x = static_cast<int>(std::lround(p.x)), y = static_cast<int>(std::lround(p.y));
  return x >= 0 && y >= 0 && x < mask.cols && y < mask.rows && mask.at<std::uint8_t>(y, x) != 0;
}

}  // namespace

void Tracker::Impl::startLoopClosure() {
  if (!config_.loop_closure) return;
  loop_ = std::make_unique<LoopClosureThread>(camera_, config_, LoopCloserConfig{}, timings_);
  // BA's moves reach the loop closer with the next keyframe (LoopClosureThread queues them).
  ba_.setWriteListener([this](const std::vector<PoseUpdate>& moved, int generation) {
    for (const PoseUpdate& u : moved) loop_->updatePose(u.keyframe_id, u.T_W_C, generation);
  });
  loop_->start();
}

void Tracker::Impl::feedLoopCloser(std::uint64_t kf_id, const RgbdFrame& frame,
                                   const Eigen::Isometry3d& T_W_C, const OrbFeatures& features,
                                   const std::vector<double>& depth_m,
                                   const std::vector<std::uint64_t>& landmark_of,
                                   std::size_t old_tracks, const MotionFilterOutput& filtered,
                                   const cv::Mat& track_mask) {
  // Masked (with its margin), held or unconfirmed pixels are never loop evidence.
  const auto excluded = [&](const cv::Point2f& p) {
    return setAt(track_mask, p) || setAt(filtered.dynamic_mask, p) ||
           setAt(filtered.held_mask, p) || setAt(filtered.unconfirmed_mask, p);
  };
  LoopKeyframeInput in;
  in.id = kf_id;
  in.T_W_C = T_W_C;
  in.generation = loop_generation_;
  // The tracks the frame had: their landmarks' descriptors at the tracked pixels.
  std::vector<std::uint64_t> ids(old_tracks);
  for (std::size_t i = 0; i < old_tracks; ++i) ids[i] = tracks_[i].landmark_id;
  cv::Mat track_descriptors;
  std::vector<std::uint8_t> bad;
  map_.descriptorsOf(ids, track_descriptors, bad);
  in.descriptors = track_descriptors;
  for (std::size_t i = 0; i < old_tracks; ++i) {
    const cv::Point2f& p = tracks_[i].px;
    in.keypoints.emplace_back(p, 31.f);
    in.depth_m.push_back(
        sampleDepth(frame.depth_m, p.x, p.y, config_.depth_min_m, config_.depth_max_m));
    in.is_static.push_back(!bad[i] && !excluded(p) ? 1 : 0);
    in.landmark_ids.push_back(ids[i]);
  }
  // The keyframe's own ORB keypoints (cells without a track).
  for (std::size_t i = 0; i < features.keypoints.size(); ++i) {
    in.keypoints.push_back(features.keypoints[i]);
    in.depth_m.push_back(depth_m[i]);
    in.is_static.push_back(excluded(features.keypoints[i].pt) ? 0 : 1);
    in.landmark_ids.push_back(landmark_of[i]);
  }
  if (!features.descriptors.empty()) in.descriptors.push_back(features.descriptors);
  if (in.descriptors.empty()) in.descriptors = cv::Mat(0, 32, CV_8UC1);
  loop_->addKeyframe(std::move(in));
}

void Tracker::Impl::applyLoopCorrections(const std::vector<LoopCorrection>& corrections,
                                         Eigen::Isometry3d* T_W_C_frame) {
  for (const LoopCorrection& c : corrections) {
    if (c.keyframes.empty()) continue;
    ScopedStageTimer timer(timings_, "loop_apply");
    // The frames after the reference keyframe move with it (their records are relative to it).
    const Eigen::Isometry3d T_W_ref_before = map_.keyframePose(ref_kf_);
    const std::vector<PoseUpdate> moved = map_.applyLoopCorrection(c);
    const Eigen::Isometry3d move = map_.keyframePose(ref_kf_) * T_W_ref_before.inverse();
    T_W_last_ = move * T_W_last_;
    last_depth_.T_W_C = move * last_depth_.T_W_C;
    ref_T_W_C_ = move * ref_T_W_C_;
    if (T_W_C_frame != nullptr) *T_W_C_frame = move * *T_W_C_frame;
    loop_generation_ = c.generation;
    {
      std::lock_guard<std::mutex> lock(stats_mutex_);
      ++stats_.loop_closures;
    }
    ba_.queueUpdates(moved);  // to the mapping backends, after the BA's earlier moves
  }
}

void Tracker::Impl::landLoopCorrections(Eigen::Isometry3d* T_W_C_frame) {
  // The loop thread is waited for first: the BA result written next tells it its moves with
  // the next keyframe, never in the middle of a pass. The correction lands after that result
  // (it moves the BA's poses; a BA window taken before it would be dropped as stale).
  std::vector<LoopCorrection> corrections;
  if (loop_) {
    ScopedStageTimer wait(timings_, "loop_wait");
    corrections = loop_->waitIdle();
  }
  if (config_.bundle_adjustment) ba_.applyFinished();
  applyLoopCorrections(corrections, T_W_C_frame);
}

}  // namespace dynamap
