// Starting in a saved map: place recognition over every loaded keyframe, then relocalization
// against the landmarks around the best-ranked ones.

#include <algorithm>
#include <stdexcept>

#include "dynamap/core/tracking/tracker_impl.hpp"

namespace dynamap {
namespace {

/// Keyframes ranked by place recognition that relocalization tries, best first.
constexpr int kPlaceCandidates = 3;

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
  map_.restore(std::move(contents));
  if (map_.keyframeCount() > 0) loaded_places_ = std::move(places);
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
  const auto places = loaded_places_->query(
      features.descriptors, [](int) { return true; }, kPlaceCandidates);
  for (const PlaceCandidate& place : places) {
    const auto kf = static_cast<std::uint64_t>(place.keyframe);
    const Eigen::Isometry3d T_W_kf = map_.keyframePose(kf);
    std::vector<std::uint64_t> around =
        map_.keyframesNear(T_W_kf, config_.kf_max_translation_m, config_.kf_max_rotation_deg);
    if (std::find(around.begin(), around.end(), kf) == around.end())
      around.insert(around.begin(), kf);
    RelocalizationResult reloc = relocalizer_.relocalizeAgainst(
        features, frame.depth_m, map_.landmarksOf(around), camera_, T_W_kf);
    if (reloc.ok) return reloc;
  }
  return {};
}

// Outside the (widened) motion mask first, then outside the movers only (held-back objects,
// e.g. a teddy taken for a person, may fill the view), as solvePose() does.
void Tracker::Impl::relocalizeInLoadedMap(const RgbdFrame& frame, const cv::Mat& gray,
                                          const MotionFilterOutput& filtered,
                                          const MotionFilterOutput& widened,
                                          TrackingResult& result) {
  result.status = FrameStatus::kLost;
  result.T_W_C = T_W_last_;
  tracks_.clear();
  RelocalizationResult reloc = relocalizeOutside(frame, gray, widened.dynamic_mask);
  if (!reloc.ok && !widened.unconfirmed_mask.empty()) {
    reloc = relocalizeOutside(frame, gray, certainMask(widened));
  }
  if (!reloc.ok) return;
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

}  // namespace dynamap
