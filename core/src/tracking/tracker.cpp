#include "dynamap/core/tracker.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "dynamap/core/tracking/tracker_impl.hpp"

namespace dynamap {
namespace {

/// A dropped track farther than this many PnP thresholds from its landmark's projection moved.
constexpr double kMovedLandmarkFactor = 2.0;

cv::Mat toGray(const cv::Mat& image, const PinholeCamera& camera) {
  if (image.empty()) return cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
  if (image.type() == CV_8UC1) return image;
  cv::Mat gray;
  cv::cvtColor(image, gray, image.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  return gray;
}

}  // namespace

Tracker::Impl::Impl(const PinholeCamera& camera, const TrackerConfig& config,
                    TimingRecorder* timings)
    : ba_(camera, config, map_, timings),
      camera_(camera),
      config_(config),
      timings_(timings),
      extractor_(config),
      lk_(config),
      optimizer_(camera, config),
      relocalizer_(config, optimizer_) {
  startLoopClosure();  // before the BA thread: it hands the BA's moves on
  if (config_.bundle_adjustment) ba_.start();
}

// The per-frame step: match -> dynamic filter -> pose (with its fallbacks) -> keyframe -> commit.
TrackingResult Tracker::Impl::track(const RgbdFrame& frame) {
  ScopedStageTimer total(timings_, "tracking");
  ++frame_serial_;  // the searches' keypoints of the last frame are stale
  // Realtime: a loop correction lands as soon as it is ready (lockstep: at the next keyframe).
  if (loop_ && !config_.ba_lockstep) applyLoopCorrections(loop_->takeCorrections(), nullptr);
  if (frame.depth_m.empty() || cv::countNonZero(frame.depth_m) == 0) return poseWithoutDepth(frame);
  if (filter_) filter_->beginFrame(frame);
  const cv::Mat gray = toGray(frame.bgr, camera_);
  const Eigen::Isometry3d T_W_C_pred = predictPose();
  LkPyramid pyramid;
  FeatureMatches matches;
  {
    ScopedStageTimer timer(timings_, "lk");
    pyramid = lk_.buildPyramid(gray);
    matchFeatures(pyramid, T_W_C_pred, matches);
    trackProbes(pyramid, matches);
  }
  TrackingResult result;
  MotionFilterOutput widened;
  const MotionFilterOutput filtered =
      removeMovers(frame, gray, matches, T_W_C_pred, widened, result);
  if (!initialized_ && loaded_places_) {
    relocalizeInLoadedMap(frame, gray, filtered, widened, result);
  } else if (!initialized_) {
    startMap(frame, gray, filtered, widened, result);
  } else {
    Eigen::Isometry3d T_W_C = T_W_C_pred;
    refindLostLandmarks(frame, gray, widened.dynamic_mask, T_W_C_pred);
    trackLoadedLandmarksOnHeldObjects(frame, gray, widened, T_W_C_pred);
    result.status = solvePose(frame, gray, widened, T_W_C, result.inliers);
    if (result.status != FrameStatus::kLost) {
      // Held-back objects (a teddy taken for a person) are no movers: they do not count. A pose
      // from depth alone bridges the frame: its features (few, near the movers) make no keyframe.
      // A keyframe that is due where one already covers the view is not made (a revisit).
      const cv::Mat movers = certainMask(filtered);
      if (result.status != FrameStatus::kPosedByDepth &&
          needKeyframe(frame.timestamp_s, T_W_C, movers) &&
          !reuseKeyframe(frame, gray, widened.dynamic_mask, movers, T_W_C, result.inliers)) {
        result.keyframe = createKeyframe(frame, gray, T_W_C, filtered, widened.dynamic_mask);
      }
      result.T_W_C = T_W_C;
    }
  }
  commitFrame(frame, gray, std::move(pyramid), result);
  return result;
}

MotionFilterOutput Tracker::Impl::removeMovers(const RgbdFrame& frame, const cv::Mat& gray,
                                               const FeatureMatches& matches,
                                               const Eigen::Isometry3d& T_W_C_pred,
                                               MotionFilterOutput& widened,
                                               TrackingResult& result) {
  Eigen::Isometry3d T_W_C_prior = T_W_C_pred;
  const bool has_prior = filter_ && priorPose(frame, T_W_C_prior);
  const MotionFilterOutput filtered =
      runMotionFilter(frame, gray, matches, has_prior ? &T_W_C_prior : nullptr);
  result.dynamic_mask = filtered.dynamic_mask;
  result.unconfirmed_mask = filtered.unconfirmed_mask;
  result.held_mask = filtered.held_mask;
  widened = filtered;
  widened.dynamic_mask = widenedMask(filtered.dynamic_mask);
  result.dynamic_matches = dropDynamic(matches, widened);
  result.tracked_features = static_cast<int>(tracks_.size());
  return filtered;
}

void Tracker::Impl::startMap(const RgbdFrame& frame, const cv::Mat& gray,
                             const MotionFilterOutput& filtered, const MotionFilterOutput& widened,
                             TrackingResult& result) {
  result.status = FrameStatus::kLost;
  result.T_W_C = T_W_last_;
  tracks_.clear();
  // The first frame starts the map at the origin; a restart after a long loss starts a new
  // part of the map where the camera was last seen.
  Eigen::Isometry3d T_W_C = T_W_last_;  // a copy: a loop correction landing moves both
  result.keyframe = createKeyframe(frame, gray, T_W_C, filtered, initialMask(gray, widened));
  if (result.keyframe) {
    initialized_ = true;
    lost_streak_ = 0;
    result.status = FrameStatus::kTracked;
    result.T_W_C = T_W_last_;
    result.inliers = static_cast<int>(tracks_.size());
  }
}

// The pose from the tracks outside the movers; failing that, with the held-back tracks added;
// failing that, relocalized against the map outside the (widened) mask, then outside the movers
// with evidence of their own only; failing that, from the depth of the static pixels aligned to
// the last frame's (a view filled by people, where no features are left to relocalize with).
FrameStatus Tracker::Impl::solvePose(const RgbdFrame& frame, const cv::Mat& gray,
                                     const MotionFilterOutput& widened, Eigen::Isometry3d& T_W_C,
                                     int& inliers) {
  if (estimatePose(frame, T_W_C, inliers) || rescuePose(frame, T_W_C, inliers)) {
    return FrameStatus::kTracked;
  }
  if (relocalize(frame, gray, widened.dynamic_mask, T_W_C, inliers) ||
      (!held_.empty() && relocalize(frame, gray, certainMask(widened), T_W_C, inliers))) {
    return FrameStatus::kRelocalized;
  }
  return alignToLastDepth(frame, widened.dynamic_mask, T_W_C) ? FrameStatus::kPosedByDepth
                                                              : FrameStatus::kLost;
}

// The dense fallback: the static depth aligned to the last tracked frame's, from the predicted
// pose; used only when the geometry pins the pose down and it stays near the prediction.
bool Tracker::Impl::alignToLastDepth(const RgbdFrame& frame, const cv::Mat& moving_mask,
                                     Eigen::Isometry3d& T_W_C) {
  if (!config_.depth_fallback || !last_tracked_ || last_depth_.depth_m.empty()) return false;
  ScopedStageTimer timer(timings_, "depth_alignment");
  PosedDepth reference = last_depth_;
  if (!reference.moving_mask.empty()) reference.moving_mask = widenedMask(reference.moving_mask);
  const PosedDepth current{frame.depth_m, moving_mask, predictPose()};
  const DepthAlignment aligned = alignDepth(reference, current, camera_);
  const Eigen::Isometry3d step = current.T_W_C.inverse() * aligned.T_W_C;
  constexpr double kMaxStepM = 0.2, kMaxStepRad = 15.0 * M_PI / 180.0;
  if (!aligned.accepted || step.translation().norm() > kMaxStepM ||
      Eigen::AngleAxisd(step.linear()).angle() > kMaxStepRad) {
    return false;
  }
  T_W_C = aligned.T_W_C;
  return true;
}

void Tracker::Impl::commitFrame(const RgbdFrame& frame, const cv::Mat& gray, LkPyramid pyramid,
                                TrackingResult& result) {
  if (result.status != FrameStatus::kLost) cullMovedLandmarks(result.T_W_C);
  dropped_.clear();
  // The tracks of a frame posed by depth alone failed to give its pose: the next frame starts
  // afresh, as after a lost one, but from this pose. (The frame's status, not a flag a frame
  // that starts the map would leave stale: that frame's new tracks must stay.)
  const bool posed_by_depth = result.status == FrameStatus::kPosedByDepth;
  if (posed_by_depth) tracks_.clear();
  const int restart = config_.restart_after_lost_frames;
  if (result.status == FrameStatus::kLost) {
    result.T_W_C = T_W_last_;
    tracks_.clear();
    last_tracked_ = false;
    // Lost for long (relocalization keeps failing, e.g. the map's texture is masked): restart.
    if (initialized_ && restart > 0 && ++lost_streak_ >= restart) initialized_ = false;
  } else {
    // Frames posed by depth alone count as lost for the restart: the map restarts at their pose.
    lost_streak_ = posed_by_depth ? lost_streak_ + 1 : 0;
    if (restart > 0 && lost_streak_ >= restart) initialized_ = false;
    velocity_ = last_tracked_ ? T_W_last_.inverse() * result.T_W_C : Eigen::Isometry3d::Identity();
    T_W_last_ = result.T_W_C;
    last_tracked_ = true;
    // A copy: the caller may reuse its buffers for the next frame.
    if (config_.depth_fallback) {
      last_depth_ = {frame.depth_m.clone(), result.dynamic_mask, T_W_last_};
    }
  }
  result.is_keyframe = static_cast<bool>(result.keyframe);
  record(frame.timestamp_s, result.status, result.T_W_C);
  countStatus(result.status, result.is_keyframe);
  prev_pyramid_ = std::move(pyramid);
  refillProbes(gray);
  // A grey input is used as is: copy it so the caller may reuse its buffer.
  prev_gray_ = gray.data == frame.bgr.data ? gray.clone() : gray;
}

// A frame without depth (a colour frame with no depth frame near it, a blank depth image) is
// posed by LK + PnP from the last frame's tracks but changes nothing: no motion filter, no
// keyframe, no new tracks or velocity. The next frame is matched against the last frame with
// depth, as if this one were not there, so keeping such frames costs the other poses nothing.
TrackingResult Tracker::Impl::poseWithoutDepth(const RgbdFrame& frame) {
  TrackingResult result;
  result.status = FrameStatus::kLost;
  result.T_W_C = T_W_last_;
  if (initialized_ && last_tracked_ && !tracks_.empty()) {
    const std::vector<FeatureTrack> saved = tracks_;
    const Eigen::Isometry3d T_W_C_pred = predictPose();
    FeatureMatches matches;
    {
      ScopedStageTimer timer(timings_, "lk");
      matchFeatures(lk_.buildPyramid(toGray(frame.bgr, camera_)), T_W_C_pred, matches);
    }
    Eigen::Isometry3d T_W_C = T_W_C_pred;
    if (estimatePose(frame, T_W_C, result.inliers)) {
      result.status = FrameStatus::kTracked;
      result.T_W_C = T_W_C;
    }
    result.tracked_features = static_cast<int>(tracks_.size());
    tracks_ = saved;
  }
  record(frame.timestamp_s, result.status, result.T_W_C);
  countStatus(result.status, false);
  return result;
}

Eigen::Isometry3d Tracker::Impl::predictPose() const {
  return last_tracked_ ? T_W_last_ * velocity_ : T_W_last_;
}

void Tracker::Impl::matchFeatures(const LkPyramid& cur, const Eigen::Isometry3d& T_W_C_pred,
                                  FeatureMatches& matches) {
  if (tracks_.empty() || prev_pyramid_.empty()) {
    tracks_.clear();
    return;
  }
  std::vector<std::uint64_t> ids(tracks_.size());
  for (std::size_t i = 0; i < tracks_.size(); ++i) ids[i] = tracks_[i].landmark_id;
  std::vector<Eigen::Vector3d> p_W;
  map_.landmarkPositions(ids, p_W);
  // Constant-velocity prior: the landmark projected with the predicted pose seeds LK.
  const Eigen::Isometry3d T_C_W = T_W_C_pred.inverse();
  std::vector<cv::Point2f> prev_px(tracks_.size()), cur_px(tracks_.size());
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    prev_px[i] = tracks_[i].px;
    cur_px[i] = tracks_[i].px;
    const Eigen::Vector3d p_C = T_C_W * p_W[i];
    if (p_C.z() <= 0.05) continue;
    const Eigen::Vector2d uv = camera_.project(p_C);
    if (uv.x() >= 0 && uv.y() >= 0 && uv.x() < camera_.width && uv.y() < camera_.height) {
      cur_px[i] = cv::Point2f(static_cast<float>(uv.x()), static_cast<float>(uv.y()));
    }
  }
  std::vector<std::uint8_t> ok;
  lk_.track(prev_pyramid_, cur, prev_px, cur_px, ok, config_.lk_backward_levels);
  std::vector<FeatureTrack> kept;
  kept.reserve(tracks_.size());
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    if (!ok[i]) continue;
    FeatureTrack t = tracks_[i];
    t.px = cur_px[i];
    kept.push_back(t);
    matches.prev_px.push_back(prev_px[i]);
    matches.cur_px.push_back(cur_px[i]);
    matches.ids.push_back(t.landmark_id);
  }
  tracks_.swap(kept);
}

MotionFilterOutput Tracker::Impl::runMotionFilter(const RgbdFrame& frame, const cv::Mat& gray,
                                                  const FeatureMatches& matches,
                                                  const Eigen::Isometry3d* T_W_C_prior) {
  if (!filter_) return {};
  ScopedStageTimer timer(timings_, "motion_filter");
  MotionFilterInput input;
  if (T_W_C_prior != nullptr) {
    input.has_prior = true;
    input.T_prev_cur = T_W_last_.inverse() * *T_W_C_prior;
    input.T_W_C = *T_W_C_prior;
  }
  input.frame = &frame;
  input.prev_gray = prev_gray_.empty() ? &gray : &prev_gray_;
  input.cur_gray = &gray;
  input.matches = &matches;
  std::vector<std::uint8_t> proven(matches.cur_px.size(), 0);  // tracks first, probes after
  for (std::size_t i = 0; i < proven_static_.size() && i < proven.size(); ++i) {
    proven[i] = proven_static_[i];
  }
  input.proven_static = &proven;
  return filter_->filter(input);
}

cv::Mat Tracker::Impl::widenedMask(const cv::Mat& dynamic_mask) const {
  const int r = config_.dynamic_margin_px;
  if (r <= 0 || dynamic_mask.empty() || cv::countNonZero(dynamic_mask) == 0) return dynamic_mask;
  // Distance to the nearest masked pixel: one pass, whatever the margin (a dilation with a
  // disc of 2r+1 costs r times more).
  cv::Mat dist;
  cv::distanceTransform(dynamic_mask != 255, dist, cv::DIST_L2, 3);
  return dist <= static_cast<float>(r);
}

// Pose from the tracks the motion filter held back only for lack of proof that their object
// stands still, with the others: a last resort when the rest of the image cannot hold a pose
// (a teddy taken for a person at start-up, in front of walkers). RANSAC still drops movers.
bool Tracker::Impl::rescuePose(const RgbdFrame& frame, Eigen::Isometry3d& T_W_C, int& inliers) {
  if (held_.empty()) return false;
  const std::size_t own = tracks_.size();
  tracks_.insert(tracks_.end(), held_.begin(), held_.end());
  if (estimatePose(frame, T_W_C, inliers)) return true;
  tracks_.resize(own);
  return false;
}

// The map starts from the features outside the motion regions; when those are too few to
// track with (fewer than min_tracked_features: a teddy taken for a person fills the view at
// start-up), from those outside the regions with evidence of motion. Nothing has shown it
// stands still yet on a first frame, so movers among them are left to RANSAC and to
// cullMovedLandmarks().
cv::Mat Tracker::Impl::initialMask(const cv::Mat& gray, const MotionFilterOutput& out) {
  if (out.unconfirmed_mask.empty() || cv::countNonZero(out.unconfirmed_mask) == 0) {
    return out.dynamic_mask;
  }
  const std::size_t outside = extractOrb(gray, out.dynamic_mask).keypoints.size();
  if (static_cast<int>(outside) >= config_.min_tracked_features) return out.dynamic_mask;
  return certainMask(out);
}

cv::Mat Tracker::Impl::certainMask(const MotionFilterOutput& out) const {
  if (out.unconfirmed_mask.empty() || out.dynamic_mask.empty()) return out.dynamic_mask;
  cv::Mat certain = out.dynamic_mask.clone();
  certain.setTo(0, out.unconfirmed_mask);
  return certain;
}

int Tracker::Impl::dropDynamic(const FeatureMatches& matches, const MotionFilterOutput& out) {
  // The landmark tracks come first in `matches`, the motion probes after them.
  const bool has_flags = out.match_is_dynamic.size() == matches.cur_px.size() &&
                         out.match_is_dynamic.size() >= tracks_.size();
  const bool has_mask = !out.dynamic_mask.empty() && out.dynamic_mask.type() == CV_8UC1;
  held_.clear();
  if (!has_flags && !has_mask) return 0;
  int dropped = 0;
  dropped_.clear();
  std::vector<FeatureTrack> kept;
  kept.reserve(tracks_.size());
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    bool dynamic = has_flags && out.match_is_dynamic[i] != 0;
    if (!dynamic && has_mask) {
      const int x = static_cast<int>(tracks_[i].px.x + 0.5f);
      const int y = static_cast<int>(tracks_[i].px.y + 0.5f);
      dynamic = x >= 0 && y >= 0 && x < out.dynamic_mask.cols && y < out.dynamic_mask.rows &&
                out.dynamic_mask.at<std::uint8_t>(y, x) == 255;
    }
    if (dynamic) {
      ++dropped;
      dropped_.push_back(tracks_[i]);
      if (i < out.match_held.size() && out.match_held[i] != 0) held_.push_back(tracks_[i]);
    } else {
      kept.push_back(tracks_[i]);
    }
  }
  tracks_.swap(kept);
  return dropped;
}

// A dropped track whose landmark no longer projects onto it with the frame's pose has moved:
// its landmark must not reach BA or relocalization again. Static landmarks that a (too large)
// mask covered still project onto their tracks and stay usable.
void Tracker::Impl::cullMovedLandmarks(const Eigen::Isometry3d& T_W_C) {
  if (dropped_.empty()) return;
  std::vector<std::uint64_t> ids(dropped_.size()), bad;
  for (std::size_t i = 0; i < dropped_.size(); ++i) ids[i] = dropped_[i].landmark_id;
  std::vector<Eigen::Vector3d> p_W;
  map_.landmarkPositions(ids, p_W);
  const Eigen::Isometry3d T_C_W = T_W_C.inverse();
  const double max_px = kMovedLandmarkFactor * config_.pnp_reprojection_px;
  for (std::size_t i = 0; i < dropped_.size(); ++i) {
    const Eigen::Vector3d p_C = T_C_W * p_W[i];
    const bool moved =
        p_C.z() <= 0.05 ||
        (camera_.project(p_C) - Eigen::Vector2d(dropped_[i].px.x, dropped_[i].px.y)).norm() >
            max_px;
    if (moved) bad.push_back(ids[i]);
  }
  map_.markBad(bad);
  dropped_.clear();
}

// ---- public wrappers ----

Tracker::Tracker(const PinholeCamera& camera, const TrackerConfig& config, TimingRecorder* timings)
    : impl_(std::make_unique<Impl>(camera, config, timings)) {}

Tracker::~Tracker() {
  impl_->ba_.stop();
  if (impl_->loop_) impl_->loop_->stop();
}

void Tracker::setMotionFilter(MotionFilter* filter) { impl_->filter_ = filter; }
TrackingResult Tracker::track(const RgbdFrame& frame) { return impl_->track(frame); }
void Tracker::markBadFrame(double timestamp_s) { impl_->markBadFrame(timestamp_s); }
std::vector<PoseUpdate> Tracker::takePoseUpdates() { return impl_->ba_.takeUpdates(); }
void Tracker::finish() { impl_->finish(); }
std::vector<std::pair<double, Eigen::Isometry3d>> Tracker::finalTrajectory() const {
  return impl_->finalTrajectory();
}
std::vector<FrameStatus> Tracker::frameStatuses() const { return impl_->frameStatuses(); }
std::vector<double> Tracker::badFrameTimestamps() const { return impl_->badFrameTimestamps(); }
std::vector<KeyframeInfo> Tracker::keyframes() const { return impl_->map_.keyframes(); }
TrackerStats Tracker::stats() const { return impl_->stats(); }
MapContents Tracker::mapContents() const { return impl_->map_.contents(); }
void Tracker::loadMap(MapContents contents) { impl_->loadMap(std::move(contents)); }

}  // namespace dynamap
