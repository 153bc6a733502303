#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "dynamap/core/dynamic/class_table.hpp"
#include "dynamap/core/dynamic/depth_check.hpp"
#include "dynamap/core/dynamic/nms.hpp"
#include "dynamap/core/dynamic/object_pixels.hpp"
#include "dynamap/core/dynamic/object_tracks.hpp"
#include "dynamap/core/dynamic_config.hpp"

namespace dynamap {

enum class FusionMode : std::uint8_t {
  kGeometry,  ///< dynamic-point clusters grown on depth only
  kDetector,  ///< every high-dynamic box, cut by depth (naive baseline, no motion check)
  kBoth,      ///< boxes decided moving by their dynamic points + clusters outside boxes
};

/// What fusion decided about one detection in the current frame.
struct ObjectDecision {
  Detection detection;
  double weight = 0.0;     ///< class motion prior
  int points = 0;          ///< tracked points on the object's own pixels
  int dynamic_points = 0;  ///< of which dynamic
  int proven_points = 0;   ///< of which landmarks the pose from proven-static ones held
  /// A person's box (a high-dynamic detection) covers much of its box: its points and flags
  /// may be the person's (a walker passing in front of a chair).
  bool under_person = false;
  bool moving_now = false;  ///< evidence in this frame
  bool moving = false;      ///< after hysteresis (what is masked)
  bool carried = false;     ///< not detected in this frame: its track carried by the flow
  /// Masked only because it has not yet shown that it stands still: nothing of its own (flags,
  /// smoothed evidence, anchors, slow moves) says it moves.
  bool unconfirmed = false;
  /// Motion evidence of its own in this frame: flags, anchors clearly off, or the smoothed
  /// evidence still above its threshold. Masked without it, it is only held back.
  bool motion_now = false;
  int quiet_frames = 0;  ///< observed frames with static evidence since it last moved
  double depth_m = 0.0;  ///< depth mode of the object (0 = no depth)
  bool has_position = false;
  cv::Vec3d p_W;       ///< centroid of its pixels in the world (with FusionEvidence::has_pose)
  AnchorCheck anchor;  ///< its points against their world anchors (with point ids and a pose)
};

/// What, besides the point flags, fuse() may rely on in this frame.
struct FusionEvidence {
  /// The point flags carry information (the geometric check was not degenerate).
  bool flags_valid = true;
  /// The camera motion the flags were measured against was fitted without the detected
  /// objects (enough background): only then do an object's quiet points say it stands still.
  bool background_fit = true;
  /// Previous-frame pixel of each point (empty: no flow). Detections (computed on the previous
  /// frame) and undetected tracks are moved by the median flow of the points inside them.
  std::vector<cv::Point2f> prev_points;
  /// Per point (empty: none): static over time (a landmark several keyframes saw). Only these
  /// carve static pixels out of a moving region: one frame's quiet flag is no proof when the
  /// camera motion was measured among movers.
  std::vector<std::uint8_t> proven_static;
  /// Per point (empty: none): FeatureMatches::ids, to follow an object's points over time.
  std::vector<std::uint64_t> point_ids;
  /// The camera pose (camera -> world) from landmarks proven static, and the intrinsics
  /// (fx, fy, cx, cy): an object's world position over time (has_pose false: not used).
  bool has_pose = false;
  cv::Matx44d T_W_C = cv::Matx44d::eye();
  cv::Vec4d K;
  /// CV_8UC1 (empty: none), 255 = pixels on a large plane (floor, wall; findSupportPlanes): no
  /// object's own. A box carried onto the floor, or the floor at a walker's feet, is not masked.
  cv::Mat planes;
  /// An earlier depth frame and its pose (null: none; needs has_pose): a cluster of dynamic
  /// points whose grown region that view saw in place is no mover (cluster_max_consistent).
  const DepthView* view = nullptr;
};

struct FusionResult {
  cv::Mat mask;            ///< CV_8UC1, 255 = moving
  cv::Mat static_objects;  ///< CV_8UC1, 255 = pixels of detected objects decided not moving
  /// CV_8UC1, 255 = masked pixels of unconfirmed objects only (ObjectDecision::unconfirmed):
  /// what the tracker may fall back on when the rest of the image cannot hold a pose.
  cv::Mat unconfirmed;
  /// CV_8UC1, 255 = masked pixels of objects without motion evidence of their own in this frame
  /// (ObjectDecision::motion_now false): held back only until they prove still. Wider than
  /// `unconfirmed` (slow moves and no-verdict anchors count here too).
  cv::Mat held;
  /// CV_8UC1, 255 = pixels of objects confirmed static over time (static_confirm_frames).
  cv::Mat confirmed;
  /// CV_8UC1, 255 = masked pixels of moving objects that are not people: class-less movers
  /// and moved objects of the detector's other classes (a pushed chair). Mapping's vote on what
  /// a mover left unmasked before anything found it reaches further beside these.
  cv::Mat moved_objects;
  std::vector<ObjectDecision> objects;
  int clusters = 0;      ///< dynamic-point clusters grown into regions outside objects
  int seen_through = 0;  ///< regions the dense check added (DynamicMotionFilter)
};

/// Fuses dynamic points and detections into a motion mask, with per-object temporal state
/// (objects are associated frame to frame by box IoU, boxes moved with the flow).
/// Keeping an object of a high-dynamic class (a person) takes evidence gathered over time: it
/// is masked until static_confirm_frames observed frames, measured against a background-only
/// camera motion, showed it still; one frame of clear motion masks it again. A low-dynamic
/// object (a chair) is kept until its smoothed evidence says it moves. A moving object the
/// detector misses is still masked for track_max_missed_frames frames (its box carried by the
/// flow). With evidence.flags_valid = false (degenerate geometric check) objects keep their
/// state and no clusters are grown. Not thread-safe (one caller).
class RegionFusion {
 public:
  RegionFusion(const DynamicConfig& config, const ClassTable& classes);

  FusionResult fuse(FusionMode mode, const cv::Mat& depth_m, const std::vector<cv::Point2f>& points,
                    const std::vector<std::uint8_t>& point_is_dynamic,
                    const std::vector<Detection>& detections,
                    const FusionEvidence& evidence = FusionEvidence());

 private:
  struct Frame;  ///< one fuse() call's inputs and masks (region_fusion.cpp)

  /// Drops a high-dynamic detection that overlaps (IoU >= 0.6) a better-scored detection of a
  /// class that does not move by itself: the detector's two labels of one object.
  std::vector<Detection> oneLabelPerObject(const std::vector<Detection>& in) const;
  /// True if a person's box (a high-dynamic detection or last frame's track, not a mover)
  /// covers kUnderPersonShare of the box of `object` (of another class).
  bool underPerson(const Detection& object, const std::vector<Detection>& detections) const;
  /// A new mover whose points are mostly proven static: not something that moved in.
  bool provenStaticMover(const ObjectDecision& d) const;
  /// A decision on `detection` with its class's weight, nothing measured yet.
  ObjectDecision newDecision(const Detection& detection) const;
  /// Moves every track's box by the median flow of the points inside it.
  void propagateTracks(const std::vector<cv::Point2f>& points, const FusionEvidence& evidence);
  /// Decides and masks each detection, its next track into `next`; returns, per track of the
  /// last frame, whether a detection continued it.
  std::vector<bool> fuseDetections(Frame& f, const std::vector<Detection>& detections,
                                   std::vector<ObjectTrack>& next, FusionResult& result) const;
  /// Decides and masks the tracks no detection continued (for track_max_missed_frames).
  void carryUndetected(Frame& f, const std::vector<bool>& matched,
                       const std::vector<Detection>& detections, std::vector<ObjectTrack>& next,
                       FusionResult& result) const;
  /// Confirmed objects out of the mask, clusters grown, the masks' margins.
  void finishMasks(Frame& f, FusionResult& result) const;
  /// The object's depth cut in `box` (objectPixels(); the box without depth).
  cv::Mat depthCut(const Frame& f, const cv::Rect& box, ObjectDecision& d,
                   const ObjectTrack* prev) const;
  /// The object's own pixels in `box` (depthCut()); counts the points on them into d, its world
  /// position and its anchors against `prev` (its track in the last frame, may be null).
  cv::Mat objectRegion(const Frame& f, const cv::Rect& box, ObjectDecision& d,
                       const ObjectTrack* prev) const;
  /// objectRegion() of a detection whose track is tracks_[track] (-1: none); without one, in
  /// kBoth, the track whose anchors hold its points (then `track` and d are set anew), else the
  /// remembered still object's (*remembered set; `track` stays -1).
  cv::Mat detectedRegion(const Frame& f, const cv::Rect& box, ObjectDecision& d, int& track,
                         const ObjectTrack** remembered) const;
  /// True if tracks_[t], not continued by a detection, is carried by the flow this frame.
  bool carried(std::size_t t, const cv::Size& image) const;
  /// Remembers the tracks that end this frame and were confirmed still; forgets old ones.
  void rememberEndedStill(const std::vector<bool>& matched, const cv::Size& image);
  /// Marks the object's pixels claimed and masks (moving, static points carved out) or keeps it.
  void applyObject(Frame& f, ObjectDecision& d, cv::Mat& region, const cv::Rect& box,
                   FusionResult& result) const;

  DynamicConfig config_;
  ClassTable classes_;
  std::vector<ObjectTrack> tracks_;
  long frame_ = 0;  ///< fuse() calls so far
  /// Still objects whose tracks ended (remember_still_frames), and the frame each is forgotten.
  std::vector<ObjectTrack> remembered_;
  std::vector<long> remembered_until_;
};

}  // namespace dynamap
