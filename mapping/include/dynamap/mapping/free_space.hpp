#pragma once

#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "dynamap/core/camera.hpp"

namespace dynamap {

struct FreeSpaceOptions {
  bool enabled = true;
  int neighbours = 2;           ///< keyframes compared on each side (earlier and later)
  double margin_m = 0.06;       ///< a point must lie this far in front of what a view saw...
  double margin_per_m2 = 0.02;  ///< ... plus this times depth^2 (sensor noise grows with z^2)
  int min_area_px = 600;        ///< smaller flagged regions (full resolution) are noise...
  int fringe_px = 0;            ///< ...unless within this distance of the keyframe's own mask
  double max_depth_m = 4.0;     ///< farther points are not checked
};

/// One keyframe as the free-space check sees it: the nearest surface in a 10 px window at half
/// resolution (so depth edges and small pose errors flag nothing), and its camera-to-world pose.
struct FreeSpaceView {
  cv::Mat near_half_m;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
};

FreeSpaceView makeFreeSpaceView(const cv::Mat& depth_m, const Eigen::Isometry3d& T_W_C);

/// Free-space consistency between keyframes: a pixel whose 3-D point lies clearly in front of
/// the surface that another keyframe saw along the same ray was not there at that other time:
/// something moved in (other keyframe earlier) or out (later). Only "in front" counts, so a
/// disocclusion never does and anything that stays where it is (a standing person, the teddy)
/// is never flagged. It catches the movers that the tracker's masks miss (the first keyframe,
/// a walker at the image border), using the neighbours' views of the space they occupied.
/// Returns CV_8UC1 at the resolution of depth_m, 255 = flagged. Flagged regions smaller than
/// options.min_area_px are dropped as noise, except those within options.fringe_px of
/// `dynamic_mask` (255 = moving; may be empty): the thin rim of a masked mover that the mask
/// missed. Thread-safe (pure function).
cv::Mat freeSpaceViolations(const PinholeCamera& camera, const cv::Mat& depth_m,
                            const Eigen::Isometry3d& T_W_C,
                            const std::vector<const FreeSpaceView*>& others,
                            const FreeSpaceOptions& options,
                            const cv::Mat& dynamic_mask = cv::Mat());

}  // namespace dynamap
