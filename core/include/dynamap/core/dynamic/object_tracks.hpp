#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "dynamap/core/dynamic/nms.hpp"

namespace dynamap {

/// The temporal state of one detected object, carried from frame to frame by RegionFusion.
struct ObjectTrack {
  cv::Rect2f box;  ///< in the newest frame (propagated with the flow when not detected)
  int class_id = -1;
  double score = 0.0;    ///< smoothed motion evidence (low-dynamic classes)
  int quiet_frames = 0;  ///< observed frames with clear static evidence since it last moved
  int missed = 0;        ///< frames since the detector last reported it
  double depth_m = 0.0;  ///< depth mode of its pixels when last seen (0 = unknown)
  bool has_anchor = false;
  cv::Vec3d anchor_W;  ///< world position where its current run of quiet frames began
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

}  // namespace dynamap
