#pragma once

// Fusion tests with a still camera: a tracked point every 10 px of a 640 x 480 image, none
// flagged, and the evidence of a pose (K of freiburg3) with, optionally, each point's id.

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "dynamap/core/dynamic/region_fusion.hpp"

namespace dynamap::test {

inline std::vector<cv::Point2f> pointGrid() {
  std::vector<cv::Point2f> points;
  for (int y = 5; y < 480; y += 10)
    for (int x = 5; x < 640; x += 10) points.emplace_back(float(x), float(y));
  return points;
}

inline FusionEvidence stillCameraEvidence(std::size_t points, bool with_ids) {
  FusionEvidence ev;
  ev.has_pose = true;
  ev.K = cv::Vec4d(535.4, 539.2, 320.1, 247.6);
  if (with_ids)
    for (std::size_t i = 0; i < points; ++i) ev.point_ids.push_back(i);
  return ev;
}

}  // namespace dynamap::test
