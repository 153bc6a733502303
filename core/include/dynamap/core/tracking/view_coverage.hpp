#pragma once

// Which parts of a view showed static scene, on a coarse grid: what a keyframe holds of the map,
// and how much of a new view the keyframes near it already hold (revisits, tracker_revisit.cpp).

#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "dynamap/core/camera.hpp"

namespace dynamap {

/// Side of a coverage cell, pixels.
constexpr int kCoverageCellPx = 16;

/// CV_8U, one element per kCoverageCellPx cell of a width x height image: 1 where less than
/// half of the cell lies under `movers` (CV_8U, 255 = a mover; empty = none).
cv::Mat staticCells(const cv::Mat& movers, int width, int height);

/// A keyframe as coverage sees it: its pose and static cells (empty: static everywhere, as a
/// saved map's keyframes).
struct CoverageView {
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  cv::Mat static_cells;
};

struct CoverageQuery {
  const PinholeCamera* camera = nullptr;
  const cv::Mat* depth_m = nullptr;  ///< CV_32F, the frame's depth
  const cv::Mat* movers = nullptr;   ///< CV_8U, 255 = a mover; may be empty
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  double depth_min_m = 0.1;
  double depth_max_m = 10.0;
};

/// Share of the frame's static samples (cell centres outside the movers, with a depth) that no
/// view saw in one of its static cells: what a keyframe made here would add to the map. 0 when
/// the frame has no static sample.
double uncoveredShare(const CoverageQuery& frame, const std::vector<CoverageView>& views);

}  // namespace dynamap
