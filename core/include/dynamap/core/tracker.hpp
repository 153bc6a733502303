#pragma once

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "dynamap/core/camera.hpp"
#include "dynamap/core/frame.hpp"
#include "dynamap/core/map_contents.hpp"
#include "dynamap/core/motion_filter.hpp"
#include "dynamap/core/timing.hpp"
#include "dynamap/core/tracker_config.hpp"

namespace dynamap {

/// Outcome of Tracker::track() for one frame.
struct TrackingResult {
  FrameStatus status = FrameStatus::kLost;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  bool is_keyframe = false;
  KeyframePacketPtr keyframe;  ///< set iff is_keyframe
  int tracked_features = 0;    ///< LK matches kept
  int inliers = 0;             ///< pose inliers
  int dynamic_matches = 0;     ///< matches the motion filter rejected
  cv::Mat dynamic_mask;        ///< from the motion filter, may be empty
  /// Of dynamic_mask, the pixels masked only for lack of evidence that they stand still
  /// (MotionFilterOutput::unconfirmed_mask); may be empty.
  cv::Mat unconfirmed_mask;
  /// The part of dynamic_mask held back only for lack of evidence that it stands still
  /// (MotionFilterOutput::held_mask); may be empty.
  cv::Mat held_mask;
};

/// Counters over all frames. frames = tracked + posed_by_depth + relocalized + lost + bad_frames.
struct TrackerStats {
  std::size_t frames = 0, tracked = 0, relocalized = 0, lost = 0, keyframes = 0;
  std::size_t posed_by_depth = 0;  ///< FrameStatus::kPosedByDepth
  /// Of `keyframes`, culled later (TrackerConfig::kf_cull_redundant).
  std::size_t culled_keyframes = 0;
  std::size_t bad_frames = 0;
  std::size_t loops = 0;          ///< loops verified by the loop closer (tracking.loop_closure)
  std::size_t loop_closures = 0;  ///< pose-graph corrections applied
};

struct KeyframeInfo {
  std::uint64_t id;
  double timestamp_s;
  Eigen::Isometry3d T_W_C;
  bool culled = false;  ///< redundant, follows an older keyframe (MapKeyframe::culled)
};

/// RGB-D tracking front end: ORB features tracked by pyramidal LK, PnP-RANSAC + Ceres motion-only
/// refinement against a local map of landmarks, keyframes, local bundle adjustment on its own
/// thread and relocalization. The world frame is the camera frame of the first tracked frame.
///
/// Per frame: LK (seeded by a constant-velocity prediction, forward-backward checked) moves the
/// tracked features; with a motion filter, TrackerConfig::motion_probes extra LK points (not
/// landmarks) are appended to its matches so that it sees movers every frame; the filter's
/// dynamic matches and every feature inside its mask are dropped (a dropped landmark that no
/// longer projects onto its track with the frame's pose is marked bad: out of BA and
/// relocalization); the motion filter's mask also keeps ORB/new landmarks off movers at
/// keyframes. PnP-RANSAC + Ceres refine
/// the pose (reprojection + depth residuals); if that fails, relocalization by ORB matching
/// against recent keyframes' landmarks; otherwise kLost with the last known pose.
/// Keyframe policy (TrackerConfig): a new keyframe when tracked features < min_tracked_features,
/// or < kf_min_tracked_ratio of those of the reference keyframe, or the camera moved more than
/// kf_max_translation_m / kf_max_rotation_deg, or the median feature parallax exceeds
/// kf_max_parallax_px, or kf_max_interval_s passed since the reference keyframe. Only keyframes
/// extract ORB features (in grid cells without a tracked feature, outside the dynamic mask) and
/// create landmarks (depth in [depth_min_m, landmark_depth_max_m]).
///
/// Threading: track(), markBadFrame(), setMotionFilter(), finish() and the trajectory getters are
/// called from one (the tracking) thread. takePoseUpdates() and stats() are thread-safe.
class Tracker {
 public:
  /// `timings` may be null; it is borrowed and must outlive the tracker.
  Tracker(const PinholeCamera& camera, const TrackerConfig& config, TimingRecorder* timings);
  ~Tracker();  ///< stops and joins the BA thread
  Tracker(const Tracker&) = delete;
  Tracker& operator=(const Tracker&) = delete;

  void setMotionFilter(MotionFilter* filter);  ///< borrowed, may be null
  /// frame.bgr CV_8UC3, frame.depth_m CV_32F metres (0 = none). Never throws on bad content:
  /// an unusable frame comes back as kLost with the last known pose.
  TrackingResult track(const RgbdFrame& frame);
  /// A frame that could not be read: counted (stats().bad_frames), its timestamp kept as a
  /// kBadFrame (badFrameTimestamps()); it has no pose, so finalTrajectory() and
  /// frameStatuses() leave it out.
  void markBadFrame(double timestamp_s);
  /// Keyframe poses corrected by BA since the last call. Thread-safe.
  std::vector<PoseUpdate> takePoseUpdates();
  /// Stops the BA thread, then one BA over the keyframes made since its last run over every
  /// keyframe and a local window more (TrackerConfig::final_ba_window). Idempotent.
  void finish();

  /// One entry per frame given to track() (not bad frames): the pose relative to its reference
  /// keyframe recomposed with that keyframe's latest optimised pose.
  std::vector<std::pair<double, Eigen::Isometry3d>> finalTrajectory() const;
  std::vector<FrameStatus> frameStatuses() const;  ///< parallel to finalTrajectory()
  std::vector<double> badFrameTimestamps() const;  ///< markBadFrame()'s, in call order
  std::vector<KeyframeInfo> keyframes() const;     ///< latest optimised poses
  TrackerStats stats() const;                      ///< thread-safe
  /// The map (landmarks, keyframes and their observations) with the latest poses: the final
  /// ones after finish(). What a saved map keeps.
  MapContents mapContents() const;
  /// Starts in a saved map instead of a new one; call before the first track(). Until a frame
  /// relocalizes in it (every loaded keyframe ranked by place recognition, then PnP against the
  /// landmarks around the best ones), frames are kLost and make no keyframe; from then on poses
  /// are in the saved map's frame, its keyframes are held fixed and revisits reuse them. The
  /// frames before the first relocalization have no pose: finalTrajectory() and
  /// frameStatuses() leave them out (stats() counts them lost); but a frame whose pose, with
  /// too few inliers to track from, agrees with the frame before's is kRelocalized with it
  /// (tracking still waits).
  void loadMap(MapContents contents);

  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace dynamap
