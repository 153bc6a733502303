#pragma once

// Internal state of dynamap::Tracker, shared by core/src/tracking/tracker*.cpp.

#include <memory>
#include <mutex>
#include <optional>
#include <unordered_map>
#include <vector>

#include "dynamap/core/tracker.hpp"
#include "dynamap/core/tracking/depth_alignment.hpp"
#include "dynamap/core/tracking/feature_extractor.hpp"
#include "dynamap/core/tracking/lk_tracker.hpp"
#include "dynamap/core/tracking/local_ba.hpp"
#include "dynamap/core/tracking/local_map.hpp"
#include "dynamap/core/tracking/loop_thread.hpp"
#include "dynamap/core/tracking/place_recognition.hpp"
#include "dynamap/core/tracking/pose_optimizer.hpp"
#include "dynamap/core/tracking/relocalizer.hpp"

namespace dynamap {

/// A feature followed by LK from frame to frame; always backed by a landmark.
struct FeatureTrack {
  std::uint64_t landmark_id = 0;
  cv::Point2f px;      ///< position in the latest frame
  cv::Point2f px_ref;  ///< position in the reference keyframe (parallax test)
};

struct FrameRecord {
  double timestamp_s = 0.0;
  FrameStatus status = FrameStatus::kLost;
  bool has_ref = false;
  std::uint64_t ref_kf = 0;
  Eigen::Isometry3d T_ref_C = Eigen::Isometry3d::Identity();  ///< used when has_ref
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();    ///< used otherwise
  /// Lost before the first relocalization in a loaded map: no pose in its frame (left out of
  /// the trajectory). A frame posed by reportAgreeingPose() meanwhile has one.
  bool unposed = false;
};

/// Share of the image's pixels that `mask` (CV_8UC1, may be empty) sets.
double maskedShare(const cv::Mat& mask);

/// Whether T_W_C_b lies within max_m and max_deg of T_W_C_a.
bool smallStep(const Eigen::Isometry3d& T_W_C_a, const Eigen::Isometry3d& T_W_C_b, double max_m,
               double max_deg);

class Tracker::Impl {
 public:
  Impl(const PinholeCamera& camera, const TrackerConfig& config, TimingRecorder* timings);

  TrackingResult track(const RgbdFrame& frame);
  void markBadFrame(double timestamp_s);
  void finish();
  std::vector<std::pair<double, Eigen::Isometry3d>> finalTrajectory() const;
  std::vector<FrameStatus> frameStatuses() const;
  std::vector<double> badFrameTimestamps() const { return bad_frames_; }
  TrackerStats stats() const;
  /// tracker_load.cpp: see Tracker::loadMap().
  void loadMap(MapContents contents);

  MotionFilter* filter_ = nullptr;
  LocalMap map_;
  LocalBundleAdjuster ba_;
  std::unique_ptr<LoopClosureThread> loop_;  ///< tracking.loop_closure; null when off

 private:
  TrackingResult poseWithoutDepth(const RgbdFrame& frame);
  /// The motion filter (against priorPose() when it holds) and the tracks on its movers
  /// dropped; the filter's masks and counts into `result`, its output returned and, with the
  /// mask grown by dynamic_margin_px, in `widened`.
  MotionFilterOutput removeMovers(const RgbdFrame& frame, const cv::Mat& gray,
                                  const FeatureMatches& matches,
                                  const Eigen::Isometry3d& T_W_C_pred, MotionFilterOutput& widened,
                                  TrackingResult& result);
  /// A map's first keyframe where the camera was last seen (kLost if it cannot be made).
  void startMap(const RgbdFrame& frame, const cv::Mat& gray, const MotionFilterOutput& filtered,
                const MotionFilterOutput& widened, TrackingResult& result);
  /// The frame's pose with its fallbacks (held-back tracks, relocalization).
  FrameStatus solvePose(const RgbdFrame& frame, const cv::Mat& gray,
                        const MotionFilterOutput& widened, Eigen::Isometry3d& T_W_C, int& inliers);
  /// The frame's outcome into the tracker's state: landmarks culled, velocity or loss, records,
  /// the frame kept as the next one's previous.
  void commitFrame(const RgbdFrame& frame, const cv::Mat& gray, LkPyramid pyramid,
                   TrackingResult& result);
  Eigen::Isometry3d predictPose() const;
  void matchFeatures(const LkPyramid& cur, const Eigen::Isometry3d& T_W_C_pred,
                     FeatureMatches& matches);
  void trackProbes(const LkPyramid& cur, FeatureMatches& matches);
  void refillProbes(const cv::Mat& gray);
  MotionFilterOutput runMotionFilter(const RgbdFrame& frame, const cv::Mat& gray,
                                     const FeatureMatches& matches,
                                     const Eigen::Isometry3d* T_W_C_prior);
  int dropDynamic(const FeatureMatches& matches, const MotionFilterOutput& out);
  /// The motion mask grown by config_.dynamic_margin_px: what pose estimation keeps away from.
  cv::Mat widenedMask(const cv::Mat& dynamic_mask) const;
  /// estimatePose() with the held-back tracks added; tracks_ unchanged if it fails.
  bool rescuePose(const RgbdFrame& frame, Eigen::Isometry3d& T_W_C, int& inliers);
  bool alignToLastDepth(const RgbdFrame& frame, const cv::Mat& moving_mask,
                        Eigen::Isometry3d& T_W_C);
  /// The mask the first keyframe of a map takes its landmarks outside of.
  cv::Mat initialMask(const cv::Mat& gray, const MotionFilterOutput& out);
  /// `out`'s mask without its unconfirmed objects.
  cv::Mat certainMask(const MotionFilterOutput& out) const;
  void cullMovedLandmarks(const Eigen::Isometry3d& T_W_C);
  bool estimatePose(const RgbdFrame& frame, Eigen::Isometry3d& T_W_C, int& inliers);
  /// The pose against the tracked landmarks proven static over time (seen by at least
  /// static_prior_min_keyframes keyframes), tracks left untouched; false if too few.
  bool priorPose(const RgbdFrame& frame, Eigen::Isometry3d& T_W_C);
  bool relocalize(const RgbdFrame& frame, const cv::Mat& gray, const cv::Mat& dynamic_mask,
                  Eigen::Isometry3d& T_W_C, int& inliers);
  /// tracker_load.cpp: the first pose in a loaded map (see Tracker::loadMap()); on success the
  /// tracker is initialised with the best keyframe as its reference.
  /// Place recognition over the loaded keyframes, then PnP around the best: features outside
  /// `mask` (255 = keep away).
  RelocalizationResult relocalizeOutside(const RgbdFrame& frame, const cv::Mat& gray,
                                         const cv::Mat& mask);
  /// Whether the depth image at T_W_C agrees with `landmarks` (kMaxSeenThroughShare).
  bool depthAgrees(const LandmarkCandidates& landmarks, const Eigen::Isometry3d& T_W_C,
                   const cv::Mat& depth_m) const;
  void relocalizeInLoadedMap(const RgbdFrame& frame, const cv::Mat& gray,
                             const MotionFilterOutput& filtered, const MotionFilterOutput& widened,
                             TrackingResult& result);
  /// Before the first pose in a loaded map: `candidate` (too few inliers to start tracking) is
  /// the frame's pose if the frame before gave the same (kAgreeingMinInliers, kAgreeingStep*).
  void reportAgreeingPose(const RelocalizationResult& candidate, TrackingResult& result);
  /// In a loaded map: the saved landmarks on held-back objects (unconfirmed, no evidence of
  /// motion) found again where the saved map has them, from the predicted pose, join the tracks.
  void trackLoadedLandmarksOnHeldObjects(const RgbdFrame& frame, const cv::Mat& gray,
                                         const MotionFilterOutput& widened,
                                         const Eigen::Isometry3d& T_W_C_pred);
  /// `movers`: the frame's motion mask without held-back objects (kf_max_masked_share).
  bool needKeyframe(double timestamp_s, const Eigen::Isometry3d& T_W_C,
                    const cv::Mat& movers) const;
  /// A revisit: the nearest keyframe that covers the view becomes the reference again and the
  /// frame tracks its landmarks (pose refined with them); false (nothing changed) if none does.
  bool reuseKeyframe(const RgbdFrame& frame, const cv::Mat& gray, const cv::Mat& track_mask,
                     const cv::Mat& movers, Eigen::Isometry3d& T_W_C, int& inliers);
  /// The movers cover more than kf_max_masked_share of the frame: few tracks there mean little
  /// (needKeyframe(), revisitMinTracks()).
  bool crowdedView(const cv::Mat& movers) const;
  /// The tracks a revisit needs with the old landmarks found again (reuseKeyframe()).
  double revisitMinTracks(const cv::Mat& movers) const;
  /// The keyframes a revisit at T_W_C is judged and tracked against: the nearest 8 within the
  /// keyframe limits.
  std::vector<std::uint64_t> reuseSources(const Eigen::Isometry3d& T_W_C) const;
  /// Share of the frame's static view that the keyframes `near` did not see outside their
  /// movers (view_coverage.hpp).
  double uncoveredView(const RgbdFrame& frame, const cv::Mat& movers,
                       const Eigen::Isometry3d& T_W_C,
                       const std::vector<std::uint64_t>& near) const;
  /// Whether a keyframe made now would be redundant (tracking.kf_cull_redundant): the nearest
  /// 8 keyframes older than the bundle-adjustment window cover its static view but
  /// kf_reuse_max_uncovered_share, and their landmarks alone pose the frame within 5 cm / 3 deg
  /// of T_W_C (1 cm / 0.5 deg when culled online). `parent` = the nearest of them. Changes nothing.
  bool coveredByOlderKeyframes(const RgbdFrame& frame, const cv::Mat& gray,
                               const cv::Mat& track_mask, const cv::Mat& movers,
                               const Eigen::Isometry3d& T_W_C, std::uint64_t& parent);
  /// The keyframe that `newest` pushes out of the bundle-adjustment window is culled into its
  /// parent if coveredByOlderKeyframes() found it redundant when it was made.
  void cullRedundantKeyframe(std::uint64_t newest);
  /// At finish(): culls the keyframes found redundant that are still in the BA window.
  void cullRemainingRedundantKeyframes();
  /// Every keyframe within the keyframe limits of T_W_C, the nearest first.
  std::vector<std::uint64_t> reuseSourcesAll(const Eigen::Isometry3d& T_W_C) const;
  /// The newest local_search_keyframes keyframes, then those near T_W_C (keyframe limits).
  std::vector<std::uint64_t> localKeyframes(const Eigen::Isometry3d& T_W_C) const;
  std::vector<std::uint64_t> trackedLandmarks() const;
  /// The frame's keypoints for the searches (extractForSearch outside `track_mask`), extracted
  /// once per frame and mask: the lost-landmark search, a revisit and the redundancy check of
  /// one frame search the same ones.
  const OrbFeatures& searchKeypoints(const cv::Mat& gray, const cv::Mat& track_mask);
  /// `candidates` found among `features` by projection with T_W_C, as tracks.
  std::vector<FeatureTrack> matchLandmarks(const RgbdFrame& frame, const OrbFeatures& features,
                                           const LandmarkCandidates& candidates,
                                           const Eigen::Isometry3d& T_W_C) const;
  /// The landmarks of `sources` the tracks do not follow, found among the frame's keypoints.
  std::vector<FeatureTrack> findMapLandmarks(const RgbdFrame& frame, const cv::Mat& gray,
                                             const cv::Mat& track_mask,
                                             const Eigen::Isometry3d& T_W_C,
                                             const std::vector<std::uint64_t>& sources);
  /// Fewer tracks than refind_below_tracks: the local map's landmarks found again among the
  /// frame's keypoints outside `track_mask`, from the predicted pose.
  void refindLostLandmarks(const RgbdFrame& frame, const cv::Mat& gray, const cv::Mat& track_mask,
                           const Eigen::Isometry3d& T_W_C_pred);
  /// Adds the re-found landmarks' tracks; tracks on the same points (newer landmarks) go.
  void mergeTracks(const std::vector<FeatureTrack>& found);
  std::vector<int> searchLocalMap(const OrbFeatures& features, const std::vector<double>& depth_m,
                                  const Eigen::Isometry3d& T_W_C, std::vector<std::uint64_t>& ids);
  /// New landmarks come from outside `track_mask`; the packet carries the filter's masks.
  /// A loop correction landing here moves T_W_C.
  KeyframePacketPtr createKeyframe(const RgbdFrame& frame, const cv::Mat& gray,
                                   Eigen::Isometry3d& T_W_C, const MotionFilterOutput& filtered,
                                   const cv::Mat& track_mask);
  OrbFeatures extractOrb(const cv::Mat& gray, const cv::Mat& dynamic_mask);
  /// tracker_loop.cpp: the loop thread started, BA's moves forwarded to it (constructor).
  void startLoopClosure();
  /// The new keyframe's static features to the loop thread: the frame's new ORB keypoints
  /// (`landmark_of`: their landmark, kNoLandmark if none) and the tracks it had before them.
  void feedLoopCloser(std::uint64_t kf_id, const RgbdFrame& frame, const Eigen::Isometry3d& T_W_C,
                      const OrbFeatures& features, const std::vector<double>& depth_m,
                      const std::vector<std::uint64_t>& landmark_of, std::size_t old_tracks,
                      const MotionFilterOutput& filtered, const cv::Mat& track_mask);
  /// Loop corrections, oldest first, into the map and the tracker's state; `T_W_C_frame` (may
  /// be null): the pose of the frame being tracked, moved as its reference keyframe.
  void applyLoopCorrections(const std::vector<LoopCorrection>& corrections,
                            Eigen::Isometry3d* T_W_C_frame);
  /// ba_lockstep: waits for the loop thread (before the BA result lands), applies its
  /// corrections after that; see createKeyframe().
  void landLoopCorrections(Eigen::Isometry3d* T_W_C_frame);
  void record(double timestamp_s, FrameStatus status, const Eigen::Isometry3d& T_W_C);
  void countStatus(FrameStatus status, bool keyframe);

  PinholeCamera camera_;
  TrackerConfig config_;
  TimingRecorder* timings_;
  GridOrbExtractor extractor_;
  LkTracker lk_;
  PoseOptimizer optimizer_;
  Relocalizer relocalizer_;

  LkPyramid prev_pyramid_;
  cv::Mat prev_gray_;
  std::vector<FeatureTrack> tracks_;   ///< parallel to the matches of the current frame
  std::vector<FeatureTrack> dropped_;  ///< tracks the motion filter dropped this frame
  std::vector<FeatureTrack> held_;     ///< of which only held back (MotionFilterOutput::match_held)
  /// Per track this frame: a landmark seen by static_prior_min_keyframes keyframes that fits
  /// priorPose() (set by priorPose(), read by runMotionFilter()).
  std::vector<std::uint8_t> proven_static_;
  std::vector<cv::Point2f> probes_;       ///< motion probes in the previous frame (not landmarks)
  std::vector<std::uint64_t> probe_ids_;  ///< one per probe, kProbeIdBit | a running number
  std::uint64_t next_probe_id_ = 0;
  bool initialized_ = false;
  int lost_streak_ = 0;  ///< frames lost in a row
  bool finished_ = false;
  Eigen::Isometry3d T_W_last_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d velocity_ = Eigen::Isometry3d::Identity();  ///< T_prev_cur of the last step
  bool last_tracked_ = false;
  PosedDepth last_depth_;        ///< the last tracked frame's depth, moving mask and pose

  std::uint64_t frame_serial_ = 0;  ///< track() calls so far: which frame a cache belongs to
  struct SearchKeypoints {
    std::uint64_t frame_serial = 0;
    cv::Mat track_mask;  ///< held: its buffer cannot be another mask's while cached
    OrbFeatures features;
  };
  SearchKeypoints search_keypoints_;  ///< searchKeypoints()'s, of frame frame_serial (0: none)

  std::uint64_t ref_kf_ = 0;
  Eigen::Isometry3d ref_T_W_C_ = Eigen::Isometry3d::Identity();
  double ref_timestamp_s_ = 0.0;
  std::size_t ref_tracks_ = 0;
  /// Fewer tracks than this make a keyframe due: min_tracked_features, lower after a revisit
  /// of a keyframe with fewer points (reuseKeyframe()).
  double ref_min_tracks_ = 0.0;
  /// Keyframes found redundant when made (coveredByOlderKeyframes()) -> their parent, until
  /// they leave the bundle-adjustment window and are culled.
  std::unordered_map<std::uint64_t, std::uint64_t> redundant_into_;

  /// A loaded map not yet relocalized in: its keyframes' static descriptors, for place
  /// recognition (null otherwise).
  std::unique_ptr<PlaceRecognizer> loaded_places_;
  /// Landmarks of the loaded map (ids below it; 0 without one).
  std::uint64_t loaded_landmarks_ = 0;
  /// The last frame's candidate first pose in a loaded map (reportAgreeingPose()), if any.
  std::optional<Eigen::Isometry3d> loaded_candidate_;
  int loop_generation_ = 0;  ///< the newest loop correction applied (LoopCorrection::generation)

  std::vector<FrameRecord> records_;
  std::vector<double> bad_frames_;  ///< markBadFrame()'s timestamps (frames without a record)
  mutable std::mutex stats_mutex_;
  TrackerStats stats_;
};

}  // namespace dynamap
