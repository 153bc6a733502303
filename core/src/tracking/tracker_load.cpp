// Starting in a saved map: place recognition over every loaded keyframe, then relocalization
// against the landmarks around the best-ranked ones.

#include <algorithm>
#include <stdexcept>
#include <tuple>

#include "dynamap/core/tracking/landmark_search.hpp"
#include "dynamap/core/tracking/tracker_impl.hpp"

namespace dynamap {
namespace {

/// Keyframes ranked by place recognition that relocalization tries, best first.
constexpr int kPlaceCandidates = 3;
/// A first pose in a loaded map whose depth image sees through more than this share of the
/// landmarks around it is wrong (seenThroughShare()). Measured: right ones 0-0.09 (22 reloads
/// of reload_check.py), a wrong one 1.25 m off with 20 inliers 0.59 (teddy_dyn_crowd_dev's map,
/// run 2 among other people: a scene of dyndata's, seed 2002).
constexpr double kMaxSeenThroughShare = 0.25;
/// Fewer landmarks with a depth to compare tell nothing either way.
constexpr int kMinDepthChecks = 20;
/// reportAgreeingPose(): a pose of this many inliers or more (fewer than reloc_min_inliers) that
/// the frame before gave too, within these steps, is the frame's pose. Measured where run 2
/// starts in a crowd (teddy's map, teddy_dyn_crowd_dev played backward): the right pose came
/// back on frames 0-3 with 6-12 inliers, 1.5-4.5 cm and 1-3 degrees apart; wrong ones 0-7.
constexpr int kAgreeingMinInliers = 8;
constexpr double kAgreeingStepM = 0.05;
constexpr double kAgreeingStepDeg = 5.0;

}  // namespace

void Tracker::Impl::loadMap(MapContents contents) {
  if (initialized_ || !records_.empty()) {
    throw std::logic_error("Tracker::loadMap: call it before the first frame");
  }
  auto places = std::make_unique<PlaceRecognizer>();
  for (const auto& kf : contents.keyframes) {
    cv::Mat descriptors;
    for (const auto& o : kf.observations) {
      const Landmark& lm = contents.landmarks[o.landmark_id];
      if (!lm.bad && !lm.descriptor.empty()) descriptors.push_back(lm.descriptor);
    }
    if (!descriptors.empty()) places->add(static_cast<int>(kf.id), descriptors);
  }
  loaded_landmarks_ = contents.landmarks.size();
  map_.restore(std::move(contents));
  if (map_.keyframeCount() > 0) loaded_places_ = std::move(places);
}

bool Tracker::Impl::depthAgrees(const LandmarkCandidates& landmarks, const Eigen::Isometry3d& T_W_C,
                                const cv::Mat& depth_m) const {
  int checked = 0;
  const double share = seenThroughShare(landmarks.points, T_W_C, depth_m, camera_,
                                        config_.depth_min_m, config_.depth_max_m, &checked);
  return checked < kMinDepthChecks || share <= kMaxSeenThroughShare;
}

RelocalizationResult Tracker::Impl::relocalizeOutside(const RgbdFrame& frame, const cv::Mat& gray,
                                                      const cv::Mat& mask) {
  OrbFeatures features;
  {
    ScopedStageTimer timer(timings_, "orb");
    cv::Mat allowed;
    if (!mask.empty()) allowed = mask != 255;
    features = extractor_.extractAll(gray, allowed);
  }
  if (features.descriptors.empty()) return {};
  ScopedStageTimer timer(timings_, "relocalize_loaded");
  RelocalizationResult best;  // the candidate with most inliers, too few to accept
  const auto places = loaded_places_->query(
      features.descriptors, [](int) { return true; }, kPlaceCandidates);
  for (const PlaceCandidate& place : places) {
    const auto kf = static_cast<std::uint64_t>(place.keyframe);
    const Eigen::Isometry3d T_W_kf = map_.keyframePose(kf);
    std::vector<std::uint64_t> around =
        map_.keyframesNear(T_W_kf, config_.kf_max_translation_m, config_.kf_max_rotation_deg);
    if (std::find(around.begin(), around.end(), kf) == around.end())
      around.insert(around.begin(), kf);
    const LandmarkCandidates landmarks = map_.landmarksOf(around);
    RelocalizationResult reloc = relocalizer_.relocalizeAgainst(
        features, frame.depth_m, landmarks, camera_, T_W_kf, kAgreeingMinInliers);
    if (reloc.inliers == 0 || !depthAgrees(landmarks, reloc.T_W_C, frame.depth_m)) continue;
    if (reloc.ok) return reloc;
    if (reloc.inliers > best.inliers) best = std::move(reloc);
  }
  return best;
}

// Outside the (widened) motion mask, and, where the motion filter holds objects back (e.g. a
// teddy taken for a person; its motion filter starts cold), outside the movers only: the pose
// with more inliers wins. A held-back object the saved map holds landmarks on, at their place,
// stands where it stood; one that moved or was never mapped matches nothing or is RANSAC's
// outlier. With the teddy masked the pose stood on the far background alone and was 5 cm off
// (teddy frames 0-180 played back), with it 0.4 cm.
void Tracker::Impl::relocalizeInLoadedMap(const RgbdFrame& frame, const cv::Mat& gray,
                                          const MotionFilterOutput& filtered,
                                          const MotionFilterOutput& widened,
                                          TrackingResult& result) {
  result.status = FrameStatus::kLost;
  result.T_W_C = T_W_last_;
  tracks_.clear();
  RelocalizationResult reloc = relocalizeOutside(frame, gray, widened.dynamic_mask);
  if (maskedShare(widened.unconfirmed_mask) > 0.0) {
    RelocalizationResult with_held = relocalizeOutside(frame, gray, certainMask(widened));
    if (std::tie(with_held.ok, with_held.inliers) > std::tie(reloc.ok, reloc.inliers)) {
      reloc = std::move(with_held);
    }
  }
  if (!reloc.ok) {
    reportAgreeingPose(reloc, result);
    return;
  }
  for (std::size_t i = 0; i < reloc.landmark_ids.size(); ++i) {
    tracks_.push_back(FeatureTrack{reloc.landmark_ids[i], reloc.px[i], reloc.px[i]});
  }
  // The nearest loaded keyframe is the reference unless reuseKeyframe() below finds better.
  const auto nearest = map_.keyframesNear(reloc.T_W_C, 4.0 * config_.kf_max_translation_m,
                                          4.0 * config_.kf_max_rotation_deg);
  ref_kf_ = nearest.empty() ? map_.keyframeCount() - 1 : nearest.front();
  ref_T_W_C_ = map_.keyframePose(ref_kf_);
  ref_timestamp_s_ = frame.timestamp_s;
  ref_tracks_ = tracks_.size();
  ref_min_tracks_ = std::min(static_cast<double>(config_.min_tracked_features),
                             config_.kf_min_tracked_ratio * static_cast<double>(ref_tracks_));
  initialized_ = true;
  lost_streak_ = 0;
  loaded_places_.reset();
  result.status = FrameStatus::kRelocalized;
  result.T_W_C = reloc.T_W_C;
  result.inliers = reloc.inliers;
  // The inliers alone are few: the saved landmarks around the pose are tracked too, and the
  // nearest saved keyframe that covers the view becomes the reference (a revisit).
  reuseKeyframe(frame, gray, widened.dynamic_mask, certainMask(filtered), result.T_W_C,
                result.inliers);
}

// Where run 2 starts in a crowd that hides most of the mapped background, the right pose comes
// back frame after frame with a handful of inliers until the view clears (teddy's map,
// teddy_dyn_crowd_dev played backward: 21 frames). Tracking from such a pose failed in the
// crowd (two of 48 reloads diverged by 43-51 cm); as the frame's pose alone, reported, it loses
// nothing, and tracking still waits for reloc_min_inliers.
void Tracker::Impl::reportAgreeingPose(const RelocalizationResult& candidate,
                                       TrackingResult& result) {
  const bool agrees = candidate.inliers >= kAgreeingMinInliers && loaded_candidate_ &&
                      smallStep(*loaded_candidate_, candidate.T_W_C, kAgreeingStepM,
                                kAgreeingStepDeg);
  loaded_candidate_.reset();
  if (candidate.inliers >= kAgreeingMinInliers) loaded_candidate_ = candidate.T_W_C;
  if (!agrees) return;
  result.status = FrameStatus::kRelocalized;
  result.T_W_C = candidate.T_W_C;
  result.inliers = candidate.inliers;
}

// The motion filter of a run in a saved map starts cold: a held-back object is masked until it
// has stood still for static_confirm_frames, although the saved map holds it (run 1 kept it).
// Meanwhile the pose stood on what is left, on teddy the far background alone (4 m away), and
// slid by centimetres within a few frames, locked in by the keyframes that followed. The saved
// landmarks found again on the object, where the saved map has them, are tracked with the
// others; RANSAC in estimatePose() drops any that moved. The mask itself is the filter's.
void Tracker::Impl::trackLoadedLandmarksOnHeldObjects(const RgbdFrame& frame, const cv::Mat& gray,
                                                      const MotionFilterOutput& widened,
                                                      const Eigen::Isometry3d& T_W_C_pred) {
  if (loaded_landmarks_ == 0 || maskedShare(widened.unconfirmed_mask) == 0.0) return;
  ScopedStageTimer timer(timings_, "refind_held");
  const LandmarkCandidates candidates = landmarksWhere(
      withoutLandmarks(map_.landmarksOf(localKeyframes(T_W_C_pred)), trackedLandmarks()),
      [&](std::uint64_t id) { return id < loaded_landmarks_; });
  if (candidates.ids.empty()) return;
  // The unconfirmed mask holds the held-back objects only (certainMask() is the rest).
  mergeTracks(matchLandmarks(frame, extractor_.extractForSearch(gray, widened.unconfirmed_mask),
                             candidates, T_W_C_pred));
}

}  // namespace dynamap
