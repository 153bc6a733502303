// Revisits: where the map already has a keyframe that covers the view, a keyframe that is due
// is not made; that keyframe becomes the reference again and its landmarks are tracked, instead
// of new landmarks beside the old ones. Keyframes grow with the space explored, not with time.
#include <algorithm>
#include <cmath>
#include <unordered_set>

#include "dynamap/core/tracking/depth_sampling.hpp"
#include "dynamap/core/tracking/landmark_search.hpp"
#include "dynamap/core/tracking/tracker_impl.hpp"

namespace dynamap {
namespace {

/// The landmarks of this many of the nearest keyframes are matched to the frame.
constexpr std::size_t kReuseSourceKeyframes = 8;
/// The most a revisit's old landmarks may move a frame's pose: farther, the matches are wrong.
constexpr double kRevisitMaxStepM = 0.05;
constexpr double kRevisitMaxStepDeg = 3.0;
/// ... and the most they may lie from its own tracks for a keyframe culled during the run.
constexpr double kOnlineCullMaxStepM = 0.01;
constexpr double kOnlineCullMaxStepDeg = 0.5;

}  // namespace

bool smallStep(const Eigen::Isometry3d& T_W_C_a, const Eigen::Isometry3d& T_W_C_b, double max_m,
               double max_deg) {
  const Eigen::Isometry3d step = T_W_C_a.inverse() * T_W_C_b;
  return step.translation().norm() <= max_m &&
         Eigen::AngleAxisd(step.linear()).angle() <= max_deg * M_PI / 180.0;
}

// A track within kSamePointPx of a re-found landmark follows the same point under a newer
// landmark: the older one takes its place.
void Tracker::Impl::mergeTracks(const std::vector<FeatureTrack>& found) {
  constexpr float kSamePointPx = 2.0f;
  std::vector<FeatureTrack> kept;
  kept.reserve(tracks_.size() + found.size());
  for (const auto& t : tracks_) {
    const bool same = std::any_of(found.begin(), found.end(), [&](const FeatureTrack& f) {
      const cv::Point2f d = f.px - t.px;
      return d.x * d.x + d.y * d.y <= kSamePointPx * kSamePointPx;
    });
    if (!same) kept.push_back(t);
  }
  kept.insert(kept.end(), found.begin(), found.end());
  tracks_.swap(kept);
}

void Tracker::Impl::refindLostLandmarks(const RgbdFrame& frame, const cv::Mat& gray,
                                        const cv::Mat& track_mask,
                                        const Eigen::Isometry3d& T_W_C_pred) {
  if (static_cast<int>(tracks_.size()) >= config_.refind_below_tracks) return;
  ScopedStageTimer timer(timings_, "refind");
  mergeTracks(findMapLandmarks(frame, gray, track_mask, T_W_C_pred, localKeyframes(T_W_C_pred)));
}

double maskedShare(const cv::Mat& mask) {
  return mask.empty() ? 0.0 : cv::countNonZero(mask) / static_cast<double>(mask.total());
}

bool Tracker::Impl::crowdedView(const cv::Mat& movers) const {
  return maskedShare(movers) > config_.kf_max_masked_share;
}

std::vector<std::uint64_t> Tracker::Impl::trackedLandmarks() const {
  std::vector<std::uint64_t> ids;
  ids.reserve(tracks_.size());
  for (const auto& t : tracks_) ids.push_back(t.landmark_id);
  return ids;
}

std::vector<std::uint64_t> Tracker::Impl::localKeyframes(const Eigen::Isometry3d& T_W_C) const {
  std::vector<std::uint64_t> ids;
  const auto n = static_cast<std::int64_t>(map_.keyframeCount());
  for (std::int64_t k = n - 1; k >= std::max<std::int64_t>(0, n - config_.local_search_keyframes);
       --k) {
    ids.push_back(static_cast<std::uint64_t>(k));
  }
  if (config_.kf_reuse_distance <= 0.0) return ids;
  for (const auto k :
       map_.keyframesNear(T_W_C, config_.kf_max_translation_m, config_.kf_max_rotation_deg)) {
    if (std::find(ids.begin(), ids.end(), k) == ids.end()) ids.push_back(k);
  }
  return ids;
}

const OrbFeatures& Tracker::Impl::searchKeypoints(const cv::Mat& gray, const cv::Mat& track_mask) {
  SearchKeypoints& cache = search_keypoints_;
  const bool same_mask = cache.track_mask.data == track_mask.data &&
                         cache.track_mask.size() == track_mask.size();
  if (cache.frame_serial == frame_serial_ && same_mask) return cache.features;
  ScopedStageTimer orb_timer(timings_, "orb");
  cv::Mat allowed;
  if (!track_mask.empty()) allowed = track_mask != 255;
  cache.features = extractor_.extractForSearch(gray, allowed);
  cache.frame_serial = frame_serial_;
  cache.track_mask = track_mask;
  return cache.features;
}

// The landmarks of `sources` that the frame's tracks do not follow, found among
// the frame's ORB keypoints (outside track_mask) by projection.
std::vector<FeatureTrack> Tracker::Impl::findMapLandmarks(
    const RgbdFrame& frame, const cv::Mat& gray, const cv::Mat& track_mask,
    const Eigen::Isometry3d& T_W_C, const std::vector<std::uint64_t>& sources) {
  const LandmarkCandidates candidates =
      withoutLandmarks(map_.landmarksOf(sources), trackedLandmarks());
  return matchLandmarks(frame, searchKeypoints(gray, track_mask), candidates, T_W_C);
}

std::vector<FeatureTrack> Tracker::Impl::matchLandmarks(const RgbdFrame& frame,
                                                        const OrbFeatures& features,
                                                        const LandmarkCandidates& candidates,
                                                        const Eigen::Isometry3d& T_W_C) const {
  std::vector<double> depth(features.keypoints.size());
  for (std::size_t i = 0; i < features.keypoints.size(); ++i) {
    const cv::Point2f& p = features.keypoints[i].pt;
    depth[i] = sampleDepth(frame.depth_m, p.x, p.y, config_.depth_min_m, config_.depth_max_m);
  }
  LandmarkSearchParams params;
  params.radius_px = config_.local_search_radius_px;
  params.max_hamming = config_.local_search_max_hamming;
  const std::vector<int> match =
      searchByProjection(features, depth, candidates, T_W_C, camera_, params);
  std::vector<FeatureTrack> found;
  for (std::size_t i = 0; i < match.size(); ++i) {
    if (match[i] < 0) continue;
    const cv::Point2f& p = features.keypoints[i].pt;
    found.push_back(FeatureTrack{candidates.ids[static_cast<std::size_t>(match[i])], p, p});
  }
  return found;
}

std::vector<std::uint64_t> Tracker::Impl::reuseSourcesAll(const Eigen::Isometry3d& T_W_C) const {
  return map_.keyframesNear(T_W_C, config_.kf_max_translation_m, config_.kf_max_rotation_deg);
}

std::vector<std::uint64_t> Tracker::Impl::reuseSources(const Eigen::Isometry3d& T_W_C) const {
  std::vector<std::uint64_t> near = reuseSourcesAll(T_W_C);
  near.resize(std::min(near.size(), kReuseSourceKeyframes));
  return near;
}

// What of the frame's static view none of `near` saw outside its movers.
double Tracker::Impl::uncoveredView(const RgbdFrame& frame, const cv::Mat& movers,
                                    const Eigen::Isometry3d& T_W_C,
                                    const std::vector<std::uint64_t>& near) const {
  CoverageQuery query;
  query.camera = &camera_;
  query.depth_m = &frame.depth_m;
  query.movers = &movers;
  query.T_W_C = T_W_C;
  query.depth_min_m = config_.depth_min_m;
  query.depth_max_m = config_.depth_max_m;
  return uncoveredShare(query, map_.coverageViews(near));
}

// A keyframe about to be made where older keyframes, outside the bundle-adjustment window,
// already cover the view (a revisit reuseKeyframe() did not take: the old keyframes were too
// recent then, or the frame needed fresh landmarks to keep tracking) is redundant if their
// landmarks alone pose the frame where its own tracks do: then its fresh landmarks add nothing
// and no drift between it and the old map is locked in when it follows its parent.
bool Tracker::Impl::coveredByOlderKeyframes(const RgbdFrame& frame, const cv::Mat& gray,
                                            const cv::Mat& track_mask, const cv::Mat& movers,
                                            const Eigen::Isometry3d& T_W_C, std::uint64_t& parent) {
  if (!config_.kf_cull_redundant || config_.ba_window <= 0 || !initialized_) return false;
  const std::size_t window = static_cast<std::size_t>(config_.ba_window);
  const std::size_t n = map_.keyframeCount();  // the id the new keyframe will have
  if (n <= window) return false;
  ScopedStageTimer timer(timings_, "keyframe_cull");
  std::vector<std::uint64_t> sources;
  for (const auto k : reuseSourcesAll(T_W_C)) {
    if (k < n - window && sources.size() < kReuseSourceKeyframes) sources.push_back(k);
  }
  if (sources.empty() ||
      uncoveredView(frame, movers, T_W_C, sources) > config_.kf_reuse_max_uncovered_share) {
    return false;
  }
  // The old landmarks the frame sees: those it tracks and those found among its keypoints.
  const LandmarkCandidates old = map_.landmarksOf(sources);
  const std::unordered_set<std::uint64_t> old_ids(old.ids.begin(), old.ids.end());
  std::vector<FeatureTrack> test = findMapLandmarks(frame, gray, track_mask, T_W_C, sources);
  for (const auto& t : tracks_) {
    if (old_ids.count(t.landmark_id) != 0) test.push_back(t);
  }
  if (static_cast<int>(test.size()) < 2 * config_.min_inliers) return false;
  std::vector<FeatureTrack> saved = std::move(tracks_);
  tracks_ = std::move(test);
  Eigen::Isometry3d T = T_W_C;
  int inliers = 0;
  const bool posed = estimatePose(frame, T, inliers);
  tracks_ = std::move(saved);
  // Culled during the run (kf_cull_online), it follows its parent with the offset it has now:
  // no drift between it and the old map to lock in. Culled at finish(), after the final bundle
  // adjustment settled its pose with the old map's, the landmarks need only pose it as a revisit
  // may (Bonn x10: 33 -> 27 keyframes, every pose the same; crowded frames' old landmarks pose
  // them 1-2 cm off their own tracks).
  const bool agree = config_.kf_cull_online
                         ? smallStep(T_W_C, T, kOnlineCullMaxStepM, kOnlineCullMaxStepDeg)
                         : smallStep(T_W_C, T, kRevisitMaxStepM, kRevisitMaxStepDeg);
  if (!posed || inliers < 2 * config_.min_inliers || !agree) return false;
  parent = sources.front();
  return true;
}

// The keyframe that `newest` pushes out of the bundle-adjustment window is culled if it was
// found redundant when it was made: tracking had it while it was the newest.
void Tracker::Impl::cullRedundantKeyframe(std::uint64_t newest) {
  if (!config_.kf_cull_online || config_.ba_window <= 0) return;  // all at finish()
  const auto window = static_cast<std::uint64_t>(config_.ba_window);
  if (newest < window) return;
  const auto it = redundant_into_.find(newest - window);
  if (it == redundant_into_.end()) return;
  const std::uint64_t id = it->first, parent = it->second;
  redundant_into_.erase(it);
  if (id == ref_kf_ || !map_.cull(id, parent)) return;
  std::lock_guard<std::mutex> lock(stats_mutex_);
  ++stats_.culled_keyframes;
}

// At the end of the run the keyframes found redundant go (all of them unless kf_cull_online,
// else those still in the window: no newer keyframe pushes them out). After the final bundle
// adjustment, which solves them free, so every pose stays what it was: culled before it, tied
// to their parents with offsets the window had not settled yet, Bonn x10's ATE went 2.46 ->
// 3.65 cm.
void Tracker::Impl::cullRemainingRedundantKeyframes() {
  std::vector<std::pair<std::uint64_t, std::uint64_t>> pending(redundant_into_.begin(),
                                                               redundant_into_.end());
  std::sort(pending.begin(), pending.end());
  redundant_into_.clear();
  for (const auto& [id, parent] : pending) {
    if (!map_.cull(id, parent)) continue;
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++stats_.culled_keyframes;
  }
}

// The map covers the view if the frame then tracks kf_min_tracked_ratio of
// min_tracked_features points, and RANSAC keeps twice min_inliers of them. In a frame the movers
// fill (kf_max_masked_share) the static view holds fewer: as many as a keyframe is made for
// there (kf_crowded_min_tracks), else a revisit in a crowd makes the keyframe it was to spare
// (the Bonn slice played backward in its saved map: 58 and 49 of the old landmarks found
// again, 60 needed, 2 new keyframes for 15).
double Tracker::Impl::revisitMinTracks(const cv::Mat& movers) const {
  const double needed =
      config_.kf_min_tracked_ratio * static_cast<double>(config_.min_tracked_features);
  if (config_.kf_crowded_min_tracks <= 0 || !crowdedView(movers)) return needed;
  return std::min(needed, static_cast<double>(config_.kf_crowded_min_tracks));
}

bool Tracker::Impl::reuseKeyframe(const RgbdFrame& frame, const cv::Mat& gray,
                                  const cv::Mat& track_mask, const cv::Mat& movers,
                                  Eigen::Isometry3d& T_W_C, int& inliers) {
  if (config_.kf_reuse_distance <= 0.0) return false;
  ScopedStageTimer timer(timings_, "keyframe_reuse");
  const std::vector<std::uint64_t> near =
      map_.keyframesNear(T_W_C, config_.kf_reuse_distance * config_.kf_max_translation_m,
                         config_.kf_reuse_distance * config_.kf_max_rotation_deg,
                         frame.timestamp_s - config_.kf_reuse_min_age_s);
  if (near.empty()) return false;
  const std::uint64_t kf = near.front();
  const std::vector<std::uint64_t> sources = reuseSources(T_W_C);
  if (uncoveredView(frame, movers, T_W_C, sources) > config_.kf_reuse_max_uncovered_share) {
    return false;
  }

  const std::vector<FeatureTrack> saved = tracks_;
  mergeTracks(findMapLandmarks(frame, gray, track_mask, T_W_C, sources));
  const double needed = revisitMinTracks(movers);
  Eigen::Isometry3d T = T_W_C;
  int n = 0;
  if (static_cast<double>(tracks_.size()) < needed || !estimatePose(frame, T, n) ||
      static_cast<int>(tracks_.size()) < 2 * config_.min_inliers ||
      // The old landmarks may correct drift, not jump: farther, the matches are wrong.
      !smallStep(T_W_C, T, kRevisitMaxStepM, kRevisitMaxStepDeg)) {
    tracks_ = saved;
    return false;
  }
  T_W_C = T;
  inliers = n;
  ref_kf_ = kf;
  ref_T_W_C_ = map_.keyframePose(kf);
  ref_timestamp_s_ = frame.timestamp_s;
  ref_tracks_ = tracks_.size();
  // Fewer tracks than a new keyframe would give: the next one is due when they drop by as
  // much as from any keyframe (kf_min_tracked_ratio), not at once below min_tracked_features.
  ref_min_tracks_ = std::min(static_cast<double>(config_.min_tracked_features),
                             config_.kf_min_tracked_ratio * static_cast<double>(ref_tracks_));
  for (auto& t : tracks_) t.px_ref = t.px;
  return true;
}

}  // namespace dynamap
