// Pose estimation, relocalization, keyframes and bookkeeping of Tracker::Impl.
#include <algorithm>
#include <cmath>

#include "dynamap/core/tracking/depth_sampling.hpp"
#include "dynamap/core/tracking/landmark_search.hpp"
#include "dynamap/core/tracking/reference_blend.hpp"
#include "dynamap/core/tracking/tracker_impl.hpp"

namespace dynamap {
namespace {

constexpr int kMinInitialLandmarks = 30;

double rotationDeg(const Eigen::Isometry3d& T) {
  return Eigen::AngleAxisd(T.rotation()).angle() * 180.0 / M_PI;
}

}  // namespace

bool Tracker::Impl::estimatePose(const RgbdFrame& frame, Eigen::Isometry3d& T_W_C, int& inliers) {
  inliers = 0;
  if (static_cast<int>(tracks_.size()) < config_.min_inliers) return false;
  std::vector<std::uint64_t> ids(tracks_.size());
  for (std::size_t i = 0; i < tracks_.size(); ++i) ids[i] = tracks_[i].landmark_id;
  std::vector<Eigen::Vector3d> p_W;
  map_.landmarkPositions(ids, p_W);
  std::vector<PoseCorrespondence> corr(tracks_.size());
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    corr[i].p_W = p_W[i];
    corr[i].px = Eigen::Vector2d(tracks_[i].px.x, tracks_[i].px.y);
    corr[i].depth_m = sampleDepth(frame.depth_m, tracks_[i].px.x, tracks_[i].px.y,
                                  config_.depth_min_m, config_.depth_max_m);
  }
  const PoseEstimate est = optimizer_.estimate(corr, T_W_C, timings_);
  if (!est.ok) return false;
  std::vector<FeatureTrack> kept;
  kept.reserve(tracks_.size());
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    if (est.inlier[i]) kept.push_back(tracks_[i]);
  }
  tracks_.swap(kept);
  T_W_C = est.T_W_C;
  inliers = est.inliers;
  return true;
}

bool Tracker::Impl::priorPose(const RgbdFrame& frame, Eigen::Isometry3d& T_W_C) {
  proven_static_.clear();
  if (!initialized_ || !last_tracked_ || config_.static_prior_min_keyframes <= 0) return false;
  ScopedStageTimer timer(timings_, "motion_prior");
  std::vector<std::uint64_t> ids(tracks_.size());
  for (std::size_t i = 0; i < tracks_.size(); ++i) ids[i] = tracks_[i].landmark_id;
  std::vector<Eigen::Vector3d> p_W;
  std::vector<int> seen;
  map_.landmarkPositions(ids, p_W);
  map_.keyframeCounts(ids, seen);
  std::vector<PoseCorrespondence> corr;
  std::vector<std::size_t> track_of;
  proven_static_.assign(tracks_.size(), 0);
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    if (seen[i] < config_.static_prior_min_keyframes) continue;
    track_of.push_back(i);
    PoseCorrespondence c;
    c.p_W = p_W[i];
    c.px = Eigen::Vector2d(tracks_[i].px.x, tracks_[i].px.y);
    c.depth_m = sampleDepth(frame.depth_m, tracks_[i].px.x, tracks_[i].px.y, config_.depth_min_m,
                            config_.depth_max_m);
    corr.push_back(c);
  }
  if (static_cast<int>(corr.size()) < 2 * config_.min_inliers) return false;
  const PoseEstimate est = optimizer_.estimate(corr, T_W_C, nullptr);
  if (!est.ok) return false;
  for (std::size_t k = 0; k < track_of.size() && k < est.inlier.size(); ++k) {
    proven_static_[track_of[k]] = est.inlier[k];
  }
  T_W_C = est.T_W_C;
  return true;
}

OrbFeatures Tracker::Impl::extractOrb(const cv::Mat& gray, const cv::Mat& dynamic_mask) {
  ScopedStageTimer timer(timings_, "orb");
  cv::Mat allowed;
  if (!dynamic_mask.empty()) allowed = dynamic_mask != 255;
  std::vector<cv::Point2f> occupied;
  occupied.reserve(tracks_.size());
  for (const auto& t : tracks_) occupied.push_back(t.px);
  return extractor_.extract(gray, allowed, occupied);
}

bool Tracker::Impl::relocalize(const RgbdFrame& frame, const cv::Mat& gray,
                               const cv::Mat& dynamic_mask, Eigen::Isometry3d& T_W_C,
                               int& inliers) {
  tracks_.clear();
  OrbFeatures features;
  {
    ScopedStageTimer timer(timings_, "orb");
    cv::Mat allowed;
    if (!dynamic_mask.empty()) allowed = dynamic_mask != 255;
    features = extractor_.extractAll(gray, allowed);
  }
  const RelocalizationResult reloc =
      relocalizer_.relocalize(features, frame.depth_m, map_, camera_, T_W_last_);
  if (!reloc.ok) return false;
  for (std::size_t i = 0; i < reloc.landmark_ids.size(); ++i) {
    tracks_.push_back(FeatureTrack{reloc.landmark_ids[i], reloc.px[i], reloc.px[i]});
  }
  T_W_C = reloc.T_W_C;
  inliers = reloc.inliers;
  return true;
}

bool Tracker::Impl::needKeyframe(double timestamp_s, const Eigen::Isometry3d& T_W_C,
                                 const cv::Mat& movers) const {
  const auto n = static_cast<double>(tracks_.size());
  if (n < ref_min_tracks_ || n < config_.kf_min_tracked_ratio * ref_tracks_) {
    // Few tracks in a frame the movers fill mean nothing new to map: what is left unmasked is
    // little and near the movers, and the tracks come back when they leave. Unless they are
    // about to run out: then the pose needs the landmarks of what is left.
    if (!crowdedView(movers)) return true;
    if (n < config_.kf_crowded_min_tracks) return true;
  }
  const Eigen::Isometry3d T_ref_C = ref_T_W_C_.inverse() * T_W_C;
  if (T_ref_C.translation().norm() > config_.kf_max_translation_m) return true;
  if (rotationDeg(T_ref_C) > config_.kf_max_rotation_deg) return true;
  if (timestamp_s - ref_timestamp_s_ > config_.kf_max_interval_s) return true;
  std::vector<float> parallax;
  parallax.reserve(tracks_.size());
  for (const auto& t : tracks_) parallax.push_back(static_cast<float>(cv::norm(t.px - t.px_ref)));
  if (parallax.empty()) return true;
  auto mid = parallax.begin() + static_cast<std::ptrdiff_t>(parallax.size() / 2);
  std::nth_element(parallax.begin(), mid, parallax.end());
  return *mid > config_.kf_max_parallax_px;
}

// Landmarks of the newest keyframes that are no longer tracked (lost behind a walker, out of
// view, dropped by LK) are searched for among the new keyframe's keypoints, so the keyframe is
// tied to the old landmarks instead of starting new ones beside them.
std::vector<int> Tracker::Impl::searchLocalMap(const OrbFeatures& features,
                                               const std::vector<double>& depth_m,
                                               const Eigen::Isometry3d& T_W_C,
                                               std::vector<std::uint64_t>& ids) {
  ids.clear();
  if (!initialized_ || config_.local_search_keyframes <= 0 || features.keypoints.empty()) {
    return std::vector<int>(features.keypoints.size(), -1);
  }
  ScopedStageTimer timer(timings_, "local_search");
  const LandmarkCandidates c =
      withoutLandmarks(map_.landmarksOf(localKeyframes(T_W_C)), trackedLandmarks());
  LandmarkSearchParams params;
  params.radius_px = config_.local_search_radius_px;
  params.max_hamming = config_.local_search_max_hamming;
  ids = c.ids;
  return searchByProjection(features, depth_m, c, T_W_C, camera_, params);
}

KeyframePacketPtr Tracker::Impl::createKeyframe(const RgbdFrame& frame, const cv::Mat& gray,
                                                Eigen::Isometry3d& T_W_C,
                                                const MotionFilterOutput& filtered,
                                                const cv::Mat& track_mask) {
  std::uint64_t redundant_parent = 0;
  const bool redundant = coveredByOlderKeyframes(frame, gray, track_mask, certainMask(filtered),
                                                 T_W_C, redundant_parent);
  const OrbFeatures features = extractOrb(gray, track_mask);
  const double max_landmark_m = std::min(config_.depth_max_m, config_.landmark_depth_max_m);
  std::vector<double> depth(features.keypoints.size());
  for (std::size_t i = 0; i < features.keypoints.size(); ++i) {
    const cv::Point2f& p = features.keypoints[i].pt;
    depth[i] = sampleDepth(frame.depth_m, p.x, p.y, config_.depth_min_m, config_.depth_max_m);
  }
  std::vector<std::uint64_t> seen_ids;
  const std::vector<int> seen = searchLocalMap(features, depth, T_W_C, seen_ids);
  std::vector<int> fresh, reseen;
  for (std::size_t i = 0; i < features.keypoints.size(); ++i) {
    if (seen[i] >= 0) {
      reseen.push_back(static_cast<int>(i));
    } else if (depth[i] > 0.0 && depth[i] <= max_landmark_m) {
      fresh.push_back(static_cast<int>(i));
    }
  }
  if (!initialized_ && static_cast<int>(fresh.size()) < kMinInitialLandmarks) return nullptr;
  // ba_lockstep: the last keyframe's BA result and loop correction land here, at a point fixed
  // by the frames alone.
  if (config_.ba_lockstep) landLoopCorrections(&T_W_C);
  const std::size_t old_tracks = tracks_.size();
  std::vector<std::uint64_t> landmark_of(loop_ ? features.keypoints.size() : 0,
                                         LoopKeyframe::kNoLandmark);

  std::vector<KeyframeObservation> observations;
  observations.reserve(tracks_.size() + fresh.size() + reseen.size());
  for (const auto& t : tracks_) {
    const double z =
        sampleDepth(frame.depth_m, t.px.x, t.px.y, config_.depth_min_m, config_.depth_max_m);
    observations.push_back({t.landmark_id, Eigen::Vector2d(t.px.x, t.px.y), z});
  }
  for (const int i : reseen) {
    const cv::Point2f& p = features.keypoints[static_cast<std::size_t>(i)].pt;
    const std::uint64_t id = seen_ids[static_cast<std::size_t>(seen[static_cast<std::size_t>(i)])];
    if (loop_) landmark_of[static_cast<std::size_t>(i)] = id;
    tracks_.push_back(FeatureTrack{id, p, p});
    observations.push_back({id, Eigen::Vector2d(p.x, p.y), depth[static_cast<std::size_t>(i)]});
  }
  for (const int i : fresh) {
    const cv::Point2f& p = features.keypoints[static_cast<std::size_t>(i)].pt;
    const double z = depth[static_cast<std::size_t>(i)];
    const Eigen::Vector3d p_W = T_W_C * camera_.backProject(p.x, p.y, z);
    const std::uint64_t id = map_.addLandmark(p_W, features.descriptors.row(i));
    if (loop_) landmark_of[static_cast<std::size_t>(i)] = id;
    tracks_.push_back(FeatureTrack{id, p, p});
    observations.push_back({id, Eigen::Vector2d(p.x, p.y), z});
  }
  const cv::Mat movers = certainMask(filtered);
  const std::uint64_t kf_id =
      map_.addKeyframe(frame.timestamp_s, T_W_C, std::move(observations), maskedShare(movers),
                       staticCells(movers, camera_.width, camera_.height));
  if (redundant) redundant_into_[kf_id] = redundant_parent;
  cullRedundantKeyframe(kf_id);
  ref_kf_ = kf_id;
  ref_T_W_C_ = T_W_C;
  ref_timestamp_s_ = frame.timestamp_s;
  ref_tracks_ = tracks_.size();
  ref_min_tracks_ = config_.min_tracked_features;
  for (auto& t : tracks_) t.px_ref = t.px;
  if (config_.bundle_adjustment && !finished_) ba_.requestRun();
  if (loop_ && !finished_) {
    feedLoopCloser(kf_id, frame, T_W_C, features, depth, landmark_of, old_tracks, filtered,
                   track_mask);
  }

  auto packet = std::make_shared<KeyframePacket>();
  packet->id = kf_id;
  packet->timestamp_s = frame.timestamp_s;
  packet->T_W_C = T_W_C;
  packet->bgr = frame.bgr.clone();
  packet->depth_m = frame.depth_m.clone();
  packet->dynamic_mask = filtered.dynamic_mask.clone();
  if (!packet->dynamic_mask.empty()) packet->held_mask = filtered.held_mask.clone();
  packet->confirmed_mask = filtered.confirmed_mask.clone();
  packet->moved_object_mask = filtered.moved_object_mask.clone();
  return packet;
}

void Tracker::Impl::record(double timestamp_s, FrameStatus status, const Eigen::Isometry3d& T_W_C) {
  FrameRecord r;
  r.timestamp_s = timestamp_s;
  r.status = status;
  r.T_W_C = T_W_C;
  r.unposed = loaded_places_ != nullptr && status == FrameStatus::kLost;
  if (initialized_) {
    r.has_ref = true;
    r.ref_kf = ref_kf_;
    r.T_ref_C = map_.keyframePose(ref_kf_).inverse() * T_W_C;
  }
  records_.push_back(r);
}

void Tracker::Impl::countStatus(FrameStatus status, bool keyframe) {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  ++stats_.frames;
  if (status == FrameStatus::kTracked) ++stats_.tracked;
  if (status == FrameStatus::kRelocalized) ++stats_.relocalized;
  if (status == FrameStatus::kPosedByDepth) ++stats_.posed_by_depth;
  if (status == FrameStatus::kLost) ++stats_.lost;
  if (keyframe) ++stats_.keyframes;
}

void Tracker::Impl::markBadFrame(double timestamp_s) {
  bad_frames_.push_back(timestamp_s);
  std::lock_guard<std::mutex> lock(stats_mutex_);
  ++stats_.frames;
  ++stats_.bad_frames;
}

void Tracker::Impl::finish() {
  if (finished_) return;
  finished_ = true;
  // The last keyframe's solve is waited for and written before the thread stops: stopped while
  // it was still pending it was dropped, while running it was kept, so the final poses depended
  // on thread timing (CI's consumer test under ctest -j2: 4.5e-6 m from the CLI's).
  // The last keyframe's loop pass too; its correction lands after that solve (as at keyframes).
  landLoopCorrections(nullptr);
  ba_.stop();
  if (loop_) loop_->stop();
  if (config_.bundle_adjustment) {
    ba_.applyFinished();  // not lockstep: a solve that finished meanwhile
    // The keyframes no global BA has seen yet and a local window more (every keyframe without
    // periodic global BAs), or the newest final_ba_window: the local windows left their drift.
    const int all = static_cast<int>(map_.keyframeCount());
    const int window = config_.final_ba_window > 0 ? config_.final_ba_window
                       : config_.ba_global_every_keyframes > 0
                           ? std::min(all, ba_.runsSinceGlobal() + config_.ba_window)
                           : all;
    ba_.runOnce(window, config_.final_ba_max_iterations);
  }
  cullRemainingRedundantKeyframes();  // after the final BA: it keeps their final poses
}

std::vector<std::pair<double, Eigen::Isometry3d>> Tracker::Impl::finalTrajectory() const {
  const std::vector<KeyframeInfo> kfs = map_.keyframes();
  std::vector<ReferencedFrame> frames;
  frames.reserve(records_.size());
  for (const auto& r : records_) {
    if (r.unposed) continue;
    ReferencedFrame f;
    f.timestamp_s = r.timestamp_s;
    f.has_ref = r.has_ref;
    f.ref_kf = r.ref_kf;
    f.T_W_C_tracked = r.T_W_C;
    if (r.has_ref) f.correction = kfs.at(r.ref_kf).T_W_C * r.T_ref_C * r.T_W_C.inverse();
    frames.push_back(f);
  }
  std::vector<Eigen::Isometry3d> poses;
  if (config_.blend_reference_switches) {
    poses = blendReferenceSwitches(frames);
  } else {
    for (const auto& f : frames) poses.push_back(f.correction * f.T_W_C_tracked);
  }
  std::vector<std::pair<double, Eigen::Isometry3d>> out;
  out.reserve(frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) out.emplace_back(frames[i].timestamp_s, poses[i]);
  return out;
}

std::vector<FrameStatus> Tracker::Impl::frameStatuses() const {
  std::vector<FrameStatus> out;
  out.reserve(records_.size());
  for (const auto& r : records_) {
    if (!r.unposed) out.push_back(r.status);
  }
  return out;
}

TrackerStats Tracker::Impl::stats() const {
  TrackerStats out;
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    out = stats_;
  }
  if (loop_) out.loops = loop_->stats().loops;
  return out;
}

}  // namespace dynamap
