#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "dynamap/core/dynamic/nms.hpp"

namespace dynamap {

/// Where a tracked point of an object was in the world when first seen on it.
struct PointAnchor {
  std::uint64_t id = 0;  ///< FeatureMatches::ids
  cv::Vec3d p_W;
};

/// A tracked point of an object in the current frame: its id, pixel and depth (0 = none).
struct PointSample {
  std::uint64_t id = 0;
  cv::Point2f px;
  float depth_m = 0.f;
};

/// An object's points against where they were anchored: the median pixel distance between
/// each anchored point's world position, projected with the current pose, and where the point
/// is now, and the median depth difference there. A person standing still keeps it within the pose
/// noise over many frames; a person swaying 5 cm on the spot, or walking slowly, drifts out of it
/// while every frame-to-frame check passes.
struct AnchorCheck {
  bool checked = false;    ///< made (a frame with a pose and point ids); else all below are empty
  int points = 0;          ///< anchored in an earlier frame and seen now (with depth)
  double median_px = 0.0;  ///< their median distance
  /// Signed median of (depth measured now - anchored point's depth in this camera): a person
  /// swaying along the line of sight barely moves in the image but changes depth.
  double median_dz_m = 0.0;
  std::vector<PointAnchor> kept;   ///< earlier anchors seen now, plus the new points anchored
  std::vector<PointAnchor> fresh;  ///< every point seen now, anchored where it is now
  /// The same for the object's whole surface (checkSurface()): its points sampled
  /// kSurfaceBaselineFrames back that land on its pixels now, and their signed median depth
  /// change (m). Hundreds of depths, not a dozen features on edges: a sway along the line of
  /// sight of 2 cm at 3 m.
  int surface_points = 0;
  double surface_dz_m = 0.0;
  std::shared_ptr<const std::vector<cv::Vec3f>> surface_fresh;  ///< its surface sampled now (world)
};

/// Checks `now` against `anchors` (sorted by id) with camera pose T_W_C (camera -> world) and
/// intrinsics K = (fx, fy, cx, cy). Both outputs come back sorted by id.
AnchorCheck checkAnchors(const std::vector<PointAnchor>& anchors,
                         const std::vector<PointSample>& now, const cv::Matx44d& T_W_C,
                         const cv::Vec4d& K);

/// How far back (frames with a pose) an object's surface is compared with: 0.4 s at 30 Hz, a
/// quarter to a half of a sway's period, while the camera turns a few degrees at most (the parts
/// of a round object that it hid or showed meanwhile stay few).
constexpr int kSurfaceBaselineFrames = 12;

/// Every `stride_px`-th pixel (both ways) of `region` (CV_8UC1, 255 = in) off depth edges, as a
/// world point (camera pose T_W_C, intrinsics K = fx, fy, cx, cy).
std::vector<cv::Vec3f> sampleSurface(const cv::Mat& region, const cv::Mat& depth_m,
                                     const cv::Matx44d& T_W_C, const cv::Vec4d& K, int stride_px);

/// Projects `surface_W` (an object's surface some frames back) into the current frame: the
/// points landing on `region` with depth there within `max_dz_m` (else another surface: an
/// occluder, the floor) give out->surface_points and the signed median of (depth now - point's
/// depth) in out->surface_dz_m.
void checkSurface(const std::vector<cv::Vec3f>& surface_W, const cv::Mat& region,
                  const cv::Mat& depth_m, const cv::Matx44d& T_W_C, const cv::Vec4d& K,
                  double max_dz_m, AnchorCheck* out);

/// The temporal state of one detected object, carried from frame to frame by RegionFusion.
struct ObjectTrack {
  cv::Rect2f box;  ///< in the newest frame (propagated with the flow when not detected)
  int class_id = -1;
  double score = 0.0;    ///< smoothed motion evidence (low-dynamic classes)
  int quiet_frames = 0;  ///< observed frames with clear static evidence since it last moved
  int missed = 0;        ///< frames since the detector last reported it
  double depth_m = 0.0;  ///< depth mode of its pixels when last seen (0 = unknown)
  bool has_anchor = false;
  cv::Vec3d anchor_W;                ///< world position where its current run of quiet frames began
  std::vector<PointAnchor> anchors;  ///< its points' world positions since that run began
  /// Its surface sampled in the last frames with a pose (world; oldest first), at most
  /// kSurfaceBaselineFrames: the oldest is what checkSurface() compares with.
  /// Shared, never changed: tracks copied from frame to frame copy pointers only.
  std::deque<std::shared_ptr<const std::vector<cv::Vec3f>>> surfaces;
  /// Times its anchors showed motion that no frame-to-frame check saw (a sway, a slow step):
  /// each doubles the quiet frames it needs to be kept (at most 16 x).
  int slow_moves = 0;
  bool anchors_still = false;  ///< its anchors were within the still limit
  bool anchors_moved = false;  ///< its anchors were off by twice the still limit
  /// Seen to move, and not yet still for static_confirm_frames since (hold_moved_objects).
  bool seen_moving = false;
  bool moving = false;
};

/// Median image motion (cur - prev) of the matches whose previous pixel lies inside `box`.
/// False (and *flow untouched) when fewer than `min_points` matches are there.
bool medianFlowIn(const cv::Rect2f& box, const std::vector<cv::Point2f>& prev_px,
                  const std::vector<cv::Point2f>& cur_px, cv::Point2f* flow, int min_points = 3);

/// Association of each detection to the track of the same class with the largest box IoU
/// above `min_iou` (several detections may continue one track: the recall-oriented NMS keeps
/// overlapping boxes of one person). Returns, per detection, the index of its track or -1.
std::vector<int> associateDetections(const std::vector<Detection>& detections,
                                     const std::vector<ObjectTrack>& tracks, float min_iou);

/// The track of class `class_id` whose anchors hold the most of `ids` (sorted), if at least
/// `min_shared`: the same points followed by the flow, whatever the box became (a person half
/// hidden behind something gets a much smaller box). -1 if none.
int trackSharingPoints(const std::vector<std::uint64_t>& ids,
                       const std::vector<ObjectTrack>& tracks, int class_id, int min_shared);

}  // namespace dynamap
